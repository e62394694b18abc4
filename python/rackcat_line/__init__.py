"""A virtual EtherCAT line with the rackcat slave, for master developers.

    with VirtualLine(rackcat="build/rackcat") as line:
        my_master.open(line.master_iface)
        line.control.unplug_rim(2)
"""
from rackcat_line.control import ControlApi, ControlError
from rackcat_line.line import LineError, VirtualLine

__all__ = ["ControlApi", "ControlError", "LineError", "VirtualLine"]
__version__ = "0.1.0"
