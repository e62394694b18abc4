# Sourced helpers: a private network namespace holding a veth pair, for the demo and the wire
# scripts. Both ends live inside the namespace, so nothing touches the host's interfaces.
#   netns_up NAME IF_SLAVE IF_MASTER    netns_down NAME
netns_up() {
  local ns=$1 a=$2 b=$3
  ip netns add "$ns"
  ip -n "$ns" link add "$a" type veth peer name "$b"
  for i in "$a" "$b"; do
    ip netns exec "$ns" sysctl -qw "net.ipv6.conf.$i.disable_ipv6=1" || true
    ip -n "$ns" link set "$i" up
  done
  ip -n "$ns" link set lo up
}
netns_down() {
  local ns=$1
  ip netns pids "$ns" 2>/dev/null | xargs -r kill 2>/dev/null || true
  ip netns del "$ns" 2>/dev/null || true
}
