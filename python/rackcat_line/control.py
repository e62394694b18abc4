"""The control API of a rack running in a namespace (HTTP + JSON on 127.0.0.1 there), as
Python calls. Each call runs one small HTTP request inside the namespace (ip netns exec with
this interpreter and urllib), so nothing but iproute2 is needed."""
from __future__ import annotations

import json
import subprocess
import sys
from typing import Any, Dict, List, Mapping, Optional, Union

Json = Dict[str, Any]

_CLIENT = r"""
import json, sys, urllib.error, urllib.request
method, url, body, token = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4]
req = urllib.request.Request(url, method=method,
                             data=body.encode() if body else (b"" if method == "POST" else None))
req.add_header("Content-Type", "application/json")
if token:
    req.add_header("Authorization", "Bearer " + token)
try:
    with urllib.request.urlopen(req, timeout=10) as r:
        status, text = r.status, r.read().decode()
except urllib.error.HTTPError as e:
    status, text = e.code, e.read().decode()
print(json.dumps({"status": status, "body": text}))
"""


class ControlError(RuntimeError):
    """The API refused a request: `status` is the HTTP status, `reason` the API's message."""

    def __init__(self, method: str, path: str, status: int, reason: str) -> None:
        super().__init__(f"{method} {path}: {status}: {reason}")
        self.status = status
        self.reason = reason


class ControlApi:
    def __init__(self, exec_prefix: List[str], port: int, token: Optional[str] = None) -> None:
        self._prefix = exec_prefix
        self.port = port
        self.token = token

    # --- raw access -------------------------------------------------------------------------
    def request(self, method: str, path: str, body: Optional[Mapping[str, Any]] = None) -> Json:
        """One request; returns the JSON answer, raises ControlError on a non-2xx status."""
        url = f"http://127.0.0.1:{self.port}{path}"
        r = subprocess.run([*self._prefix, sys.executable, "-c", _CLIENT, method, url,
                            json.dumps(body) if body is not None else "", self.token or ""],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=30)
        if r.returncode != 0:
            raise ControlError(method, path, 0, r.stderr.strip() or "no answer")
        answer = json.loads(r.stdout)
        text = answer["body"]
        data: Json = json.loads(text) if text.strip() else {}
        if not 200 <= answer["status"] < 300:
            raise ControlError(method, path, answer["status"], str(data.get("error", text)))
        return data

    def get(self, path: str) -> Json:
        return self.request("GET", path)

    def post(self, path: str, body: Mapping[str, Any]) -> Json:
        return self.request("POST", path, body)

    # --- the rack -----------------------------------------------------------------------------
    def rack(self) -> Json:
        """The whole rack: RIMs, modules, fans, CPU temperature."""
        return self.get("/api/rack")

    def module(self, number: int) -> Json:
        """One module with its live channel values."""
        return self.get(f"/api/modules/{number}")

    def esm(self) -> Json:
        return self.get("/api/esm")

    def exceptions(self) -> Json:
        """The exception tree (guide §4.7)."""
        return self.get("/api/exceptions")

    def diagnosis(self) -> Json:
        """The diagnosis history 0x10F3 (ETG.1020 §13): its flags and every stored message,
        newest first, with its code, type, time, module/channel and text."""
        return self.get("/api/diagnosis")

    def diagnosis_messages(self) -> List[Json]:
        """Only the messages of the diagnosis history, newest first."""
        return list(self.diagnosis()["messages"])

    # --- fault injection ----------------------------------------------------------------------
    def set_channel(self, module: int, channel: int, value: Union[int, float]) -> Json:
        """A constant input value on one channel."""
        return self.post("/api/channel", {"module": module, "channel": channel, "value": value})

    def set_source(self, module: int, channel: int, source: str,
                   params: Optional[Mapping[str, Any]] = None) -> Json:
        """A signal source (constant, ramp, sine, noise, replay, loopback, plant, clock)."""
        body: Json = {"module": module, "channel": channel, "source": source}
        if params:
            body["params"] = dict(params)
        return self.post("/api/channel", body)

    def unplug_rim(self, rim: int, comm_error: bool = False) -> Json:
        return self.post("/api/rim/unplug", {"rim": rim, "comm_error": comm_error})

    def replug_rim(self, rim: int) -> Json:
        return self.post("/api/rim/replug", {"rim": rim})

    def set_rim_state(self, rim: int, state: str, comm_error: bool = False) -> Json:
        """state: offline, connected, online or error."""
        return self.post("/api/rim/state", {"rim": rim, "state": state, "comm_error": comm_error})

    def set_fan(self, rim: int, zone: str, rpm: float) -> Json:
        return self.post("/api/fan", {"rim": rim, "zone": zone, "rpm": rpm})

    def set_cpu_temperature(self, celsius: float, immediate: bool = True) -> Json:
        return self.post("/api/cpu_temperature", {"celsius": celsius, "immediate": immediate})

    def wiring_fault(self, module: int, channel: int, fault: str) -> Json:
        return self.post("/api/wiring_fault", {"module": module, "channel": channel,
                                               "fault": fault})
