#!/usr/bin/env bash
# The native tests under AddressSanitizer and UndefinedBehaviorSanitizer: both C modules
# (maizeviz/_loops.c, maizeviz/mesh/_packets.c) built with gcc -fsanitize=address,undefined
# into a copy of the package in a temporary folder (the work tree is left as it is), then the
# tests that call them run against that copy, libasan preloaded (Python itself is not
# instrumented) and leak checks off (CPython keeps its objects to the end). Any report fails
# the run: halt_on_error stops the process at the first, and the report files must be empty.
# Needs gcc and the venv of scripts/setup.sh. Usage: bash scripts/sanitize.sh [pytest args]
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-.venv/bin/python}
CC_SAN=${CC_SAN:-gcc}
tmp=$(mktemp -d "${TMPDIR:-/tmp}/maizeviz-sanitize.XXXXXX")
trap 'rm -rf "$tmp"' EXIT

inc=$("$PY" -c "import sysconfig; print(sysconfig.get_paths()['include'])")
cp -r maizeviz "$tmp/maizeviz"
find "$tmp/maizeviz" -name "*.so" -delete
find "$tmp/maizeviz" -depth -name "__pycache__" -type d -exec rm -rf {} +

build() {  # source (in the package), module file name
  local src=$1 out=$2 sha
  sha=$(sha256sum "maizeviz/$src" | cut -d' ' -f1)     # as setup.py passes it
  "$CC_SAN" -shared -fPIC -g -O1 -fno-omit-frame-pointer -fsanitize=address,undefined \
    -fno-sanitize-recover=undefined -ffp-contract=off -fvisibility=hidden \
    -DPy_LIMITED_API=0x030B0000 -DMZ_SOURCE_SHA256="$sha" -I"$inc" \
    -o "$tmp/maizeviz/$out" "maizeviz/$src"
}
build _loops.c _loops.abi3.so
build mesh/_packets.c mesh/_packets.abi3.so

asan=$("$CC_SAN" -print-file-name=libasan.so)
logs="$tmp/reports"
mkdir "$logs"
export LD_PRELOAD="$asan${LD_PRELOAD:+:$LD_PRELOAD}"
export ASAN_OPTIONS="detect_leaks=0:halt_on_error=1:abort_on_error=0:exitcode=86:log_path=$logs/asan"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:exitcode=87:log_path=$logs/ubsan"
export PYTHONPATH="$tmp${PYTHONPATH:+:$PYTHONPATH}" PYTHONSAFEPATH=1   # not the work tree's
# the copy is the one imported, and it uses its sanitized modules
"$PY" -c "
import maizeviz, maizeviz.loops as l, maizeviz.mesh.packets as p
assert maizeviz.__file__.startswith('$tmp'), maizeviz.__file__
assert l.available(), l.why()
assert p.status().name == 'packets', p.status().why
print('sanitize: modules', l._loaded()[0]._name, p.status().path, sep='\n  ')"

# the sanitizer is live: a deliberate write past a buffer (4 triangles into room for 1)
# through the C function itself must be caught
canary=0
ASAN_OPTIONS="detect_leaks=0:halt_on_error=1:exitcode=86:log_path=$tmp/canary" "$PY" -c "
import numpy as np, maizeviz.loops as l
v, o = np.zeros((1, 3, 3, 3)), np.empty(1)
l._lib().mz_grid_twice_areas(v.ctypes.data, 1, 3, 3, 0.0, o.ctypes.data, o.ctypes.data)
" || canary=$?
if [ "$canary" -ne 86 ] || ! grep -q "heap-buffer-overflow" "$tmp"/canary.*; then
  echo "sanitize: AddressSanitizer did not catch a known overflow (exit $canary)" >&2
  exit 1
fi
echo "sanitize: AddressSanitizer caught the known overflow (the canary)" >&2

status=0
"$PY" -m pytest -q -p no:randomly -p no:cacheprovider \
  tests/core/test_loops.py tests/core/test_loops_fuzz.py tests/core/test_simplify_batch.py \
  tests/core/test_packets.py tests/core/test_field.py tests/core/test_tiling.py "$@" || status=$?
if compgen -G "$logs/*" >/dev/null; then
  echo "sanitize: reports:" >&2
  cat "$logs"/* >&2
  status=${status/#0/1}
fi
if [ "$status" -ne 0 ]; then
  echo "sanitize: FAILED (exit $status)" >&2
  exit "$status"
fi
echo "sanitize: no report from AddressSanitizer or UndefinedBehaviorSanitizer" >&2
