#!/usr/bin/env bash
# What a session lent a GPU node runs there, in one call (its device time is short).
#
# Prepare here, in the checkout (ignored folders, carried by the call):
#   .whl/    cp312 manylinux wheels of usd-core, moderngl, glcontext, OpenImageIO, OpenEXR,
#            mapbox_earcut, trimesh, and `pip wheel --no-deps -w .whl .` (usdwrinkle); for
#            the farm's tests dask, distributed, partd, locket, tblib, zict, tornado (43 MB)
#   .gl/     the glvnd/EGL .debs (/work/.library/device/README.md)
#   .corpus/ a copy of ../shared/corpus (3 MB: the tests' corpus fixture needs all of it)
# then run `bash benchmarks/gpu_session.sh` there with carry [".whl", ".gl", ".corpus"].
# Each step has its own time limit, so a slow one leaves the others' results in $OUT:
#   log.txt                  everything printed
#   benchmarks-gpu.md/.json  `python -m benchmarks` (docs/benchmarks-gpu.md)
#   crests.npz, tables.npz   with EXTRAS=1 EXTRAS_S=240: benchmarks.crests_across_gl
#                            --save, --save-tables (compare them here: --compare,
#                            --compare-tables), and two files-written variants
#   draws (in log.txt)       with DRAWS=N (before the bench): benchmarks.stability --draws
#                            N at 0.01 and 0.1 degrees on this GL (docs/method.md, "Two
#                            more, found over random axes"; about 40 s for 32 on 16 cores)
set -u
# the bench gets what is left of TOTAL seconds (the call's limit, less a margin)
deadline=$((SECONDS + ${TOTAL:-570}))
OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
exec > >(tee "$OUT/log.txt") 2>&1
step() { echo; echo "=== $* ($(date -u +%T))"; }

step setup
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
vendor=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
[ -f "$vendor" ] && export __EGL_VENDOR_LIBRARY_FILENAMES=$vendor
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
    --target /tmp/site .whl/*.whl || exit 1
# the checkout's code (src first), the wheels for what it needs
export PYTHONPATH=$PWD/src:/tmp/site PYTHONUNBUFFERED=1 USDWRINKLE_CORPUS=$PWD/.corpus
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
nproc
python3 -c "from usdwrinkle.render.context import renderer_info; print(renderer_info())" || exit 1

step "tests: the quick tier on this GL (the GPU against numpy, the goldens' oracle, stability)"
# about a minute on 16 cores. Deselected: what this machine cannot do (no network for the
# wheel's build, no mypy, no console script beside its python3)
timeout ${TESTS_S:-150} python3 -m pytest -q -p no:cacheprovider -W ignore -n 16 \
    --dist loadfile -m "not slow and not realclient" -rfE \
    --deselect tests/test_wheel.py::test_wheel_ships_its_data_and_runs \
    --deselect tests/test_layers.py::test_the_api_and_the_application_layer_are_typed \
    --deselect tests/test_omissions_said.py::test_a_refusal_with_stderr_closed_still_exits_2

if [ "${DRAWS:-0}" -gt 0 ]; then
  step "stability over $DRAWS random axes on this GL"
  timeout 120 python3 -c "from benchmarks import stability as s
for d in (0.01, 0.1): print(s.draws_table(s.draws($DRAWS, d, processes=16), d))"
fi

# the bench first, so that the extras below only get what time it leaves (EXTRAS=1)
step "the bench"
timeout $((deadline - SECONDS - ${EXTRAS_S:-0})) python3 -m benchmarks \
    --json "$OUT/benchmarks-gpu.json" --markdown "$OUT/benchmarks-gpu.md"

if [ "${EXTRAS:-0}" = 1 ]; then
  # the bench's files-written rows run the default (2 readback buffers); this is the before
  step "files written, --readback-buffers 1"
  timeout 60 python3 -m benchmarks.files_written --readback-buffers 1
  # the EXR rows with the beauty alone (render --aovs color)
  step "files written, --aovs color"
  timeout 60 python3 -m benchmarks.files_written --aovs color
  step "crests on this GL"
  timeout 60 python3 -m benchmarks.crests_across_gl --save "$OUT/crests.npz"
  # the shirt's per-vertex tables, frame by frame (here: --compare-tables tables.npz)
  timeout 60 python3 -m benchmarks.crests_across_gl --save-tables "$OUT/tables.npz"
fi
step done
