#!/usr/bin/env python3
"""The layering check must find every deliberate violation of tests/layering/bad and nothing
else: each file there that says "Deliberate violation" holds exactly one forbidden #include
(coe seeing mdp, the firmware seeing the chip's internals, the frames or the host I/O, the chip
seeing the firmware, ...), every other file only allowed ones. The compiler must refuse the same
files (layering_compiler_refuses, tests/layering/CMakeLists.txt). Failing here means check_layers.py stopped
catching a kind of violation (or flags an allowed include), not that the tree is wrong.
Usage: check_detects.py [path of check_layers.py]."""
import pathlib
import subprocess
import sys

HERE = pathlib.Path(__file__).resolve().parent


def main() -> int:
    check = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else HERE / "check_layers.py"
    bad = HERE / "bad"
    expected = sorted(p.relative_to(bad).as_posix() for p in bad.rglob("*")
                      if p.suffix in (".hpp", ".cpp")
                      and "Deliberate violation" in p.read_text(encoding="utf-8"))
    run = subprocess.run([sys.executable, str(check), str(bad)], capture_output=True, text=True)
    flagged = sorted(line.split(":", 1)[0] for line in run.stdout.splitlines()
                     if " must not include " in line)
    ok = run.returncode == 1 and flagged == expected and len(expected) >= 4
    if not ok:
        print(f"check_layers exit {run.returncode}; expected violations in {expected}, "
              f"flagged {flagged}\n{run.stdout}{run.stderr}")
        return 1
    print(f"check_detects: all {len(expected)} deliberate violations found, nothing else")
    return 0


if __name__ == "__main__":
    sys.exit(main())
