#!/usr/bin/env bash
# The RIM link on a real kernel CAN stack (issue "socketcan", docs/CAN.md): boots Debian's
# kernel (linux-image-amd64) under qemu-system-x86_64 with an initramfs of busybox-static, the
# kernel's can, can-raw, can-dev and vcan modules, can_vm_test and rackcat (with the shared
# libraries ldd names); inside, creates vcan0 and runs can_vm_test, which prints one line
# "CAN_VM_RESULT PASS|FAIL ...". Where this kernel has AF_CAN and vcan0 is up, runs natively.
#
# Usage: scripts/can_vm.sh CAN_VM_TEST RACKCAT
# Exit: 0 pass, 1 fail, 77 skipped (no qemu / kernel / CAN modules / busybox-static).
set -u
SKIP=77
test_bin=${1:?usage: can_vm.sh CAN_VM_TEST RACKCAT}
rackcat=${2:?usage: can_vm.sh CAN_VM_TEST RACKCAT}

verdict() {  # reads the result line from a log file
  local line
  line=$(grep -a -m1 '^CAN_VM_RESULT' "$1" | tr -d '\r')
  if [[ -z $line ]]; then
    echo "can_vm: no result line; last console lines:"
    tail -n 30 "$1"
    exit 1
  fi
  echo "$line"
  [[ $line == "CAN_VM_RESULT PASS"* ]] && exit 0
  exit 1
}

# Natively, when the host kernel can (AF_CAN and a vcan0 that is up).
if python3 -c 'import socket; socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW)' \
  2>/dev/null && ip link show vcan0 2>/dev/null | grep -q 'UP'; then
  log=$(mktemp)
  trap 'rm -f "$log"' EXIT
  timeout 50 "$test_bin" "$rackcat" vcan0 >"$log" 2>&1
  verdict "$log"
fi

qemu=$(command -v qemu-system-x86_64) || { echo "can_vm: SKIP (no qemu-system-x86_64)"; exit $SKIP; }
kernel=$(ls /boot/vmlinuz-* 2>/dev/null | sort -V | tail -n 1)
[[ -n $kernel && -r $kernel ]] || { echo "can_vm: SKIP (no readable /boot/vmlinuz-*)"; exit $SKIP; }
kver=${kernel#/boot/vmlinuz-}
moddir=/lib/modules/$kver/kernel
busybox=$(command -v busybox) || { echo "can_vm: SKIP (no busybox)"; exit $SKIP; }
if ldd "$busybox" >/dev/null 2>&1; then
  echo "can_vm: SKIP ($busybox is not statically linked: install busybox-static)"
  exit $SKIP
fi
mods=(net/can/can net/can/can-raw drivers/net/can/dev/can-dev drivers/net/can/vcan)
for m in "${mods[@]}"; do
  if ! ls "$moddir/$m".ko* >/dev/null 2>&1; then
    echo "can_vm: SKIP (kernel $kver has no $m module)"
    exit $SKIP
  fi
done

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
root=$work/root
mkdir -p "$root"/{bin,proc,sys,dev,tmp,modules}
cp "$busybox" "$root/bin/busybox"
for a in sh mount insmod ip reboot sleep cat echo; do ln -s busybox "$root/bin/$a"; done
# The test binaries and every shared library they load (with the dynamic loader).
for b in "$test_bin" "$rackcat"; do
  cp "$b" "$root/bin/"
  for lib in $(ldd "$b" | grep -o '/[^ ]*'); do
    cp -L --parents "$lib" "$root/" 2>/dev/null
  done
done
for m in "${mods[@]}"; do
  f=$(ls "$moddir/$m".ko* | head -n 1)
  name=$(basename "$m").ko
  case $f in
    *.xz) xz -dc "$f" >"$root/modules/$name" ;;
    *.zst) zstd -dcq "$f" >"$root/modules/$name" ;;
    *.gz) gzip -dc "$f" >"$root/modules/$name" ;;
    *) cp "$f" "$root/modules/$name" ;;
  esac
done
cat >"$root/init" <<'INIT'
#!/bin/sh
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev
for m in can can-raw can-dev vcan; do insmod /modules/$m.ko || echo "insmod $m failed"; done
ip link set lo up
ip link add dev vcan0 type vcan && ip link set vcan0 up
/bin/can_vm_test /bin/rackcat vcan0
reboot -f
INIT
chmod +x "$root/init"
(cd "$root" && find . | cpio -o -H newc --quiet | gzip -1) >"$work/initrd.gz"

accel=(-accel tcg)
# KVM only on request: on some hosts /dev/kvm exists but cannot run a guest (nested or
# sandboxed hypervisors); TCG boots this kernel in seconds.
if [[ ${CAN_VM_KVM:-0} == 1 && -w /dev/kvm ]]; then accel=(-enable-kvm); fi
log=$work/console.log
start=$(date +%s.%N)
timeout 55 "$qemu" "${accel[@]}" -m 512 -smp 2 -nographic -no-reboot -nodefaults -serial stdio \
  -kernel "$kernel" -initrd "$work/initrd.gz" \
  -append "console=ttyS0 quiet loglevel=3 panic=-1 rdinit=/init" >"$log" 2>&1
end=$(date +%s.%N)
echo "can_vm: VM ($kver, ${accel[*]}) ran $(awk "BEGIN{printf \"%.1f\", $end-$start}") s"
verdict "$log"
