#!/usr/bin/env bash
# What a session lent a GPU node runs there, in one call (its device time is short).
#
# Prepare here, in the checkout (ignored folders, carried by the call):
#   .whl/    cp312 manylinux wheels of usd-core, moderngl, glcontext, OpenImageIO, OpenEXR,
#            mapbox_earcut, trimesh, and `pip wheel --no-deps -w .whl .` (usdwrinkle)
#   .gl/     the glvnd/EGL .debs (/work/.library/device/README.md)
#   .corpus/ a copy of ../shared/corpus (3 MB: the tests' corpus fixture needs all of it)
# then run `bash benchmarks/gpu_session.sh` there with carry [".whl", ".gl", ".corpus"].
# Each step has its own time limit, so a slow one leaves the others' results in $OUT:
#   log.txt                  everything printed
#   benchmarks-gpu.md/.json  `python -m benchmarks` (docs/benchmarks-gpu.md)
#   crests.npz, tables.npz   with EXTRAS=1 EXTRAS_S=240: benchmarks.crests_across_gl
#                            --save, --save-tables (compare them here: --compare,
#                            --compare-tables), and two files-written variants
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
export PYTHONPATH=/tmp/site PYTHONUNBUFFERED=1 USDWRINKLE_CORPUS=$PWD/.corpus
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
nproc
python3 -c "from usdwrinkle.render.context import renderer_info; print(renderer_info())" || exit 1

step "tests: the GPU oracle, the resolve, the mip chains, crush and relax against numpy, multi-frame identity"
timeout ${TESTS_S:-120} python3 -m pytest -q -p no:cacheprovider -n 8 --dist loadfile \
    tests/test_gpu_oracle.py tests/test_resolve.py tests/test_mipmaps.py \
    tests/test_crush_relax.py \
    "tests/test_whole_frames.py::test_every_file_is_the_frame_it_names"

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
