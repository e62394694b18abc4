"""VirtualLine: `rackcat run` on the slave end of a veth pair in a private network namespace;
the master end (`master_iface`) stays in the caller's namespace for any master to open."""
from __future__ import annotations

import os
import shutil
import signal
import subprocess
import tempfile
import time
from pathlib import Path
from types import TracebackType
from typing import List, Optional, Sequence, Type, Union

from rackcat_line.control import ControlApi
from rackcat_line.netns import Namespace

PathLike = Union[str, "os.PathLike[str]"]


class LineError(RuntimeError):
    """The line could not be set up; the message holds rackcat's own output."""


class VirtualLine:
    """One virtual line. Use it as a context manager (or call start() and close())."""

    def __init__(self, rackcat: PathLike = "rackcat", config: Optional[PathLike] = None,
                 slaves: int = 1, control_port: int = 8765, extra_args: Sequence[str] = (),
                 start_timeout_s: float = 10.0) -> None:
        self.rackcat = str(shutil.which(str(rackcat)) or rackcat)
        self.config = None if config is None else str(Path(config).resolve())
        self.slaves = slaves
        self.control_port = control_port
        self.extra_args = list(extra_args)
        self.start_timeout_s = start_timeout_s
        self._ns = Namespace()
        self._state_dir: Optional[str] = None
        self._log_path: Optional[Path] = None
        self._proc: Optional[subprocess.Popen[bytes]] = None
        self.control = ControlApi(self._ns.exec_prefix(), control_port)

    # --- what the master needs ------------------------------------------------------------
    @property
    def master_iface(self) -> str:
        """The interface the master opens (in the caller's network namespace)."""
        return self._ns.master_iface

    @property
    def namespace(self) -> str:
        return self._ns.name

    def log(self) -> str:
        """rackcat's output so far."""
        return self._log_path.read_text(errors="replace") if self._log_path else ""

    # --- lifetime ------------------------------------------------------------------------------
    def start(self) -> "VirtualLine":
        if os.geteuid() != 0:
            raise LineError("a virtual line needs root: it creates a network namespace and a "
                            "veth pair (run as root, e.g. with sudo)")
        if shutil.which("ip") is None:
            raise LineError("iproute2 ('ip') is not installed")
        self._state_dir = tempfile.mkdtemp(prefix="rackcat-line-")
        os.chmod(self._state_dir, 0o755)
        self._log_path = Path(self._state_dir) / "rackcat.log"
        try:
            self._ns.create()
            cmd: List[str] = [self.rackcat, "run", "--iface", self._ns.slave_iface,
                              "--slaves", str(self.slaves), "--state-dir",
                              str(Path(self._state_dir) / "state"),
                              "--control-port", str(self.control_port), "--no-pty"]
            if self.config:
                cmd += ["--config", self.config]
            cmd += self.extra_args
            with open(self._log_path, "wb") as log:
                self._proc = subprocess.Popen(self._ns.exec_prefix() + cmd, stdout=log,
                                              stderr=subprocess.STDOUT)
            self._wait_ready()
        except BaseException:
            self.close()
            raise
        return self

    def _wait_ready(self) -> None:
        deadline = time.monotonic() + self.start_timeout_s
        while time.monotonic() < deadline:
            assert self._proc is not None
            if self._proc.poll() is not None:
                raise LineError(f"rackcat exited with {self._proc.returncode}:\n{self.log()}")
            if "control API on" in self.log():
                # The API's bearer token: rackcat writes it into its state directory.
                token = Path(self._state_dir or "") / "state" / "control-token"
                if token.exists():
                    self.control.token = token.read_text().strip()
                return
            if "--no-control" in self.extra_args and "slave(s) on" in self.log():
                return
            time.sleep(0.05)
        raise LineError(f"rackcat did not start within {self.start_timeout_s} s:\n{self.log()}")

    def close(self) -> None:
        """Stops rackcat (SIGINT, then SIGKILL), removes namespace, interfaces and files."""
        if self._proc is not None and self._proc.poll() is None:
            self._proc.send_signal(signal.SIGINT)
            try:
                self._proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait()
        self._ns.destroy()
        if self._state_dir:
            shutil.rmtree(self._state_dir, ignore_errors=True)
            self._state_dir = None

    def __enter__(self) -> "VirtualLine":
        return self.start()

    def __exit__(self, exc_type: Optional[Type[BaseException]],
                 exc: Optional[BaseException], tb: Optional[TracebackType]) -> None:
        self.close()
