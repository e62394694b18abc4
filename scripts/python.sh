# Sourced: PY is the Python that has the project's packages - the virtual environment
# scripts/setup.sh creates in the checkout (.venv), or $PYTHON when set.
#   . scripts/python.sh; "$PY" script.py
_rackcat_root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
if [ -n "${PYTHON:-}" ]; then
  PY=$PYTHON
elif [ -x "$_rackcat_root/.venv/bin/python" ]; then
  PY=$_rackcat_root/.venv/bin/python
else
  echo "rackcat: no Python environment: run scripts/setup.sh first (it creates .venv)" >&2
  PY=python3
fi
unset _rackcat_root
