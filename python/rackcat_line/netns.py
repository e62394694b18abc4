"""A private network namespace holding the slave end of a veth pair; the master end stays in
the caller's namespace under a unique name (at most 15 characters, the kernel's limit)."""
from __future__ import annotations

import itertools
import os
import subprocess
from typing import List, Optional

_counter = itertools.count()


def _ip(*args: str, check: bool = True) -> subprocess.CompletedProcess[str]:
    return subprocess.run(["ip", *args], check=check, stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True)


class Namespace:
    """Use create()/destroy(), or the namespace as a context manager."""

    def __init__(self, slave_iface: str = "ecat-slave", prefix: str = "rackcat-line") -> None:
        tag = f"{os.getpid() % 100000}x{next(_counter)}"
        self.name = f"{prefix}-{tag}"
        self.slave_iface = slave_iface
        self.master_iface = f"rcm{tag}"[:15]
        self._peer = f"rcs{tag}"[:15]
        self._created = False

    def create(self) -> None:
        _ip("netns", "add", self.name)
        self._created = True
        _ip("link", "add", self.master_iface, "type", "veth", "peer", "name", self._peer)
        _ip("link", "set", self._peer, "netns", self.name)
        _ip("-n", self.name, "link", "set", self._peer, "name", self.slave_iface)
        # No IPv6 chatter (router solicitations) on the wire, from before the links are up: a
        # capture of the line holds EtherCAT frames only.
        for where, iface in ((["ip", "netns", "exec", self.name], self.slave_iface),
                             ([], self.master_iface)):
            subprocess.run([*where, "sysctl", "-qw", f"net.ipv6.conf.{iface}.disable_ipv6=1"],
                           check=False, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        for args in (["link", "set", self.master_iface, "up"],
                     ["-n", self.name, "link", "set", self.slave_iface, "up"],
                     ["-n", self.name, "link", "set", "lo", "up"]):
            _ip(*args)

    def __enter__(self) -> "Namespace":
        try:
            self.create()
        except BaseException:
            self.destroy()
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        self.destroy()

    def exec_prefix(self) -> List[str]:
        return ["ip", "netns", "exec", self.name]

    def destroy(self) -> None:
        if not self._created:
            return
        pids = _ip("netns", "pids", self.name, check=False).stdout.split()
        for pid in pids:
            try:
                os.kill(int(pid), 9)
            except (ProcessLookupError, ValueError):
                pass
        _ip("link", "del", self.master_iface, check=False)  # removes the peer too
        _ip("netns", "del", self.name, check=False)
        self._created = False

    def pids(self) -> Optional[List[int]]:
        out = _ip("netns", "pids", self.name, check=False).stdout.split()
        return [int(p) for p in out if p.isdigit()]
