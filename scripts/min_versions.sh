#!/usr/bin/env bash
# The core tests at the minimum versions pyproject.toml declares, so that a floor that lies
# fails: a second virtual environment (.venv-min) holding every runtime dependency and the
# sweep extra at its floor (numpy, scipy, pandas, pvlib, embreex, meshio, matplotlib, pyserial,
# dask, pyarrow, tqdm; scripts/floors.py), with the gui extra and the core tests' tools at
# their newest. Run after scripts/setup.sh (its system packages); idempotent.
set -euo pipefail
cd "$(dirname "$0")/.."

PY=${PYTHON:-python3}
if [ ! -x .venv-min/bin/python ]; then
  "$PY" -m venv .venv-min
fi
.venv-min/bin/python -m pip install -q --upgrade pip >/dev/null
.venv-min/bin/python scripts/floors.py > .venv-min/floors.txt
.venv-min/bin/python -m pip install -q -c .venv-min/floors.txt -e ".[gui,sweep,test-core]"
echo "min-versions: $(paste -sd ' ' .venv-min/floors.txt)" >&2
.venv-min/bin/python scripts/floors.py --check >/dev/null
.venv-min/bin/python -m pytest -q -p no:cacheprovider tests/core \
  --ignore=tests/core/test_architecture.py
