"""Runs a reproducer's master call against `rackcat run` (default rack) in a private network
namespace: `python3 reproducers/NAME.py` (as root) sets the namespace up and runs the same
file again inside it with --iface. The call prints what the master did; exit status 1 while
the bug is there, 0 once a master release fixes it."""
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def main(reproduce):
    """reproduce(iface) -> True when the bug showed."""
    if len(sys.argv) == 3 and sys.argv[1] == "--iface":
        sys.exit(1 if reproduce(sys.argv[2]) else 0)
    from matrix import Cell
    with Cell("reproducer", "default", "/tmp/rackcat-reproducers") as cell:
        cell.start_slave()
        r = subprocess.run(cell.ns_exec() + ["chrt", "-f", "10", sys.executable, sys.argv[0],
                                             "--iface", cell.if_master])
        print(f"capture: {cell.pcap}")
    if r.returncode < 0:
        print(f"the master's process died with signal {-r.returncode}: bug present")
        sys.exit(1)
    print("bug present" if r.returncode else "bug gone: the master release fixes it")
    sys.exit(r.returncode)
