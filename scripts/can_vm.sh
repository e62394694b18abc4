#!/usr/bin/env bash
# The RIM link on a real kernel CAN stack (issue "socketcan", docs/CAN.md): boots Debian's
# kernel (linux-image-amd64) under qemu-system-x86_64 with an initramfs of busybox-static, the
# kernel's can, can-raw, can-dev and vcan modules, can_vm_test and rackcat (with the shared
# libraries ldd names); inside, creates vcan0 and runs can_vm_test, which prints one line
# "CAN_VM_RESULT PASS|FAIL ...". Where this kernel has AF_CAN and vcan0 is up, runs natively.
#
# Then the EtherCAT side (tests/can_vm/ecat_over_can.py): the VM mounts this machine's root
# file system read-only over virtio-9p, chroots into it and runs pysoem against
# `rackcat run --rim-bus can:vcan1` over a veth pair, with the RIMs as processes on a vcan bus
# held to 1 Mbit/s by netem. It prints "CAN_VM_ECAT_RESULT PASS|FAIL|SKIP ..." (SKIP only when
# pysoem is not installed). Both lines must pass.
#
# Usage: scripts/can_vm.sh CAN_VM_TEST RACKCAT
# CAN_VM_LOG=FILE keeps the VM's console output. CAN_VM_TIMEOUT=SECONDS bounds the VM (default
# 150; the ctest gives the whole script 360 s, two runs): more on a machine busy with other work, where
# qemu's TCG runs slowly.
# CAN_VM_ECAT=skip_REASON skips the EtherCAT stage (the sanitizer build: wire tests run on the
# release build); its result line then reads "CAN_VM_ECAT_RESULT SKIP reason=REASON".
# Exit: 0 pass, 1 fail, 77 skipped (no qemu / kernel / CAN modules / busybox-static).
set -u
SKIP=77
test_bin=${1:?usage: can_vm.sh CAN_VM_TEST RACKCAT}
rackcat=${2:?usage: can_vm.sh CAN_VM_TEST RACKCAT}
test_bin=$(realpath "$test_bin")
rackcat=$(realpath "$rackcat")
ecat_test=$(realpath "$(dirname "$0")/../tests/can_vm/ecat_over_can.py")
check_capture=$(realpath "$(dirname "$0")/../tests/can_vm/check_can_capture.py")
. "$(dirname "$0")/python.sh" 2>/dev/null  # PY: the project's Python (.venv) with pysoem

verdict() {  # verdict LOG CAPTURE: the two result lines of the log, then the CAN capture; 0 = pass
  local line ecat cap=
  line=$(grep -a -m1 '^CAN_VM_RESULT' "$1" | tr -d '\r')
  ecat=$(grep -a -m1 '^CAN_VM_ECAT_RESULT' "$1" | tr -d '\r')
  if [[ -z $line || -z $ecat ]]; then
    echo "can_vm: a result line is missing; last console lines:"
    tail -n 40 "$1"
    return 1
  fi
  echo "$line"
  echo "$ecat"
  if [[ $ecat == "CAN_VM_ECAT_RESULT FAIL"* ]] && grep -aq '^Traceback' "$1"; then
    echo "can_vm: the EtherCAT stage's traceback:"
    sed -n '/^Traceback/,/^CAN_VM_ECAT_RESULT/p' "$1" | tr -d '\r' | head -n 40
  fi
  if [[ $ecat == "CAN_VM_ECAT_RESULT PASS"* ]]; then
    cap=$(python3 "$check_capture" "$2")
    echo "$cap"
  fi
  [[ $line == "CAN_VM_RESULT PASS"* && $ecat =~ ^CAN_VM_ECAT_RESULT\ (PASS|SKIP) ]] || return 1
  [[ -z $cap || $cap =~ ^CAN_VM_CAPTURE\ (PASS|SKIP) ]] || return 1
  return 0
}

# Natively, when the host kernel can (AF_CAN and a vcan0 that is up).
if python3 -c 'import socket; socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW)' \
  2>/dev/null && ip link show vcan0 2>/dev/null | grep -q 'UP'; then
  tmp=$(mktemp -d)
  trap 'rm -rf "$tmp"' EXIT
  timeout 50 "$test_bin" "$rackcat" vcan0 >"$tmp/log" 2>&1
  if [[ ${CAN_VM_ECAT:-run} == skip_* ]]; then
    echo "CAN_VM_ECAT_RESULT SKIP reason=${CAN_VM_ECAT#skip_}" >>"$tmp/log"
  else
    # Its own network namespace: vcan1 and the veth pair vanish with it.
    RACKCAT_CAN_CAPTURE=$tmp/can.pcapng timeout 90 unshare --net "$PY" "$ecat_test" \
      "$rackcat" >>"$tmp/log" 2>&1
  fi
  verdict "$tmp/log" "$tmp/can.pcapng"
  exit
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
# Kernel modules with their dependencies, in load order (modules.dep lists a module's
# dependencies, the ones to load first last).
depfile=/lib/modules/$kver/modules.dep
[[ -r $depfile ]] || { echo "can_vm: SKIP (no $depfile)"; exit $SKIP; }
declare -A seen=()
order=()
add_module() {  # add_module NAME-or-PATH
  local path=$1 line dep
  [[ $path == */* ]] || path=$(grep -m1 -E "/$1\.ko(\.[a-z]+)?:" "$depfile" | cut -d: -f1)
  [[ -n $path ]] || return 1
  [[ -n ${seen[$path]:-} ]] && return 0
  seen[$path]=1
  line=$(grep -m1 "^$path:" "$depfile" | cut -d: -f2)
  local deps=($line) i
  for ((i = ${#deps[@]} - 1; i >= 0; i--)); do add_module "${deps[i]}" || return 1; done
  order+=("$path")
}
for m in can can-raw can-dev vcan; do
  add_module "$m" || { echo "can_vm: SKIP (kernel $kver has no $m module)"; exit $SKIP; }
done
# The EtherCAT stage: veth, netem, and 9p over virtio for the host's root file system.
ecat_mods=1
for m in veth sch_netem virtio_pci 9pnet_virtio 9p; do add_module "$m" || ecat_mods=0; done

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
root=$work/root
mkdir -p "$root"/{bin,proc,sys,dev,tmp,modules}
cp "$busybox" "$root/bin/busybox"
for a in sh mount insmod ip reboot sleep cat echo mkdir chroot; do ln -s busybox "$root/bin/$a"; done
# The test binaries and every shared library they load (with the dynamic loader).
for b in "$test_bin" "$rackcat"; do
  cp "$b" "$root/bin/"
  for lib in $(ldd "$b" | grep -o '/[^ ]*'); do
    cp -L --parents "$lib" "$root/" 2>/dev/null
  done
done
for path in "${order[@]}"; do
  f=/lib/modules/$kver/$path
  name=$(basename "$path")
  name=${name%%.ko*}
  case $f in
    *.xz) xz -dc "$f" >"$root/modules/$name.ko" ;;
    *.zst) zstd -dcq "$f" >"$root/modules/$name.ko" ;;
    *.gz) gzip -dc "$f" >"$root/modules/$name.ko" ;;
    *) cp "$f" "$root/modules/$name.ko" ;;
  esac
  echo "$name" >>"$root/modules/order"
done
# The EtherCAT stage runs in the host's root (chroot over 9p) with the project's Python
# (.venv, scripts/python.sh). The host's /tmp stays as it is there (read-only), so a checkout
# below /tmp is visible; the writable places are tmpfs on /run (TMPDIR) and the share /run/out.
py=$("$PY" -c 'import sys; print(sys.executable)' 2>/dev/null)
if [[ ${CAN_VM_ECAT:-run} == skip_* ]]; then
  echo "CAN_VM_ECAT_RESULT SKIP reason=${CAN_VM_ECAT#skip_}" >"$root/ecat_skip"
elif [[ $ecat_mods == 1 && -n $py ]]; then
  printf 'env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin HOME=/root TMPDIR=/run/tmp PYTHONDONTWRITEBYTECODE=1 %q %q %q %q %q\n' \
    "RACKCAT_CAN_BITRATE=${RACKCAT_CAN_BITRATE:-1mbit}" RACKCAT_CAN_CAPTURE=/run/out/can.pcapng \
    "$py" "$ecat_test" "$rackcat" >"$root/stage_ecat"
fi
cat >"$root/init" <<'INIT'
#!/bin/sh
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev
for m in $(cat /modules/order); do
  # echo=1: vcan delivers frames itself, after the qdisc (netem rate in the EtherCAT stage)
  if [ "$m" = vcan ]; then p=echo=1; else p=; fi
  insmod /modules/$m.ko $p || echo "insmod $m failed"
done
ip link set lo up
ip link add dev vcan0 type vcan && ip link set vcan0 up
/bin/can_vm_test /bin/rackcat vcan0
if [ -e /ecat_skip ]; then
  cat /ecat_skip
elif [ ! -e /stage_ecat ]; then
  echo "CAN_VM_ECAT_RESULT FAIL reason=no_veth_netem_9p_modules_or_no_python3"
elif mkdir -p /host && mount -t 9p -o trans=virtio,version=9p2000.L,ro,msize=512000 hostroot /host; then
  mount -t proc proc /host/proc
  mount -t sysfs sys /host/sys
  mount -t devtmpfs dev /host/dev
  mount -t tmpfs run /host/run
  mkdir -p /host/run/tmp /host/run/out  # the writable share: the CAN capture comes back here
  mount -t 9p -o trans=virtio,version=9p2000.L,msize=512000 out /host/run/out
  chroot /host /bin/sh -c "$(cat /stage_ecat)"
else
  echo "CAN_VM_ECAT_RESULT FAIL reason=9p_mount_failed"
fi
reboot -f
INIT
chmod +x "$root/init"
(cd "$root" && find . | cpio -o -H newc --quiet | gzip -1) >"$work/initrd.gz"

accel=(-accel tcg)
# KVM only on request: on some hosts /dev/kvm exists but cannot run a guest (nested or
# sandboxed hypervisors); TCG boots this kernel in seconds.
if [[ ${CAN_VM_KVM:-0} == 1 && -w /dev/kvm ]]; then accel=(-enable-kvm); fi
run_vm() {  # run_vm: boots the VM once and judges its console; 0 = pass
  local log=$work/console.log start end
  rm -rf "$work/out" && mkdir -p "$work/out"
  start=$(date +%s.%N)
  timeout "${CAN_VM_TIMEOUT:-150}" "$qemu" "${accel[@]}" -m 1024 -smp 2 -nographic -no-reboot -nodefaults -serial stdio \
    -kernel "$kernel" -initrd "$work/initrd.gz" \
    -virtfs local,path=/,mount_tag=hostroot,security_model=none,readonly=on,multidevs=remap \
    -virtfs local,path="$work/out",mount_tag=out,security_model=none \
    -append "console=ttyS0 quiet loglevel=3 panic=-1 rdinit=/init" >"$log" 2>&1
  end=$(date +%s.%N)
  if [[ -n ${CAN_VM_LOG:-} ]]; then  # the whole console and the CAN capture, for debugging
    cp "$log" "$CAN_VM_LOG"
    cp "$work/out/can.pcapng" "$CAN_VM_LOG.pcapng" 2>/dev/null
  fi
  echo "can_vm: VM ($kver, ${accel[*]}) ran $(awk "BEGIN{printf \"%.1f\", $end-$start}") s"
  verdict "$log" "$work/out/can.pcapng"
}
# Under TCG every guest timer depends on the host scheduling qemu's vCPU threads: on a loaded
# host a vCPU can stall past the RIM heartbeat consumer time (150 ms), and the slave then
# rightly leaves OP with 0x0070. Such a failure is the host's; a defect fails twice. So one
# failed run is followed by a second, and only a second failure fails the test.
run_vm && exit 0
echo "can_vm: the first run failed (above); running the VM once more"
run_vm
