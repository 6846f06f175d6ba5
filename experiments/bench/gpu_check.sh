#!/usr/bin/env bash
# The camera loop on a real GPU (the camera-loop issue, requirement 4): which adapter
# paracosm picks with no flag, render frames/s, the pedestrian study's CPU and wall time per
# test for each camera system under test, throughput with every core, and dataset export.
#
#   bash experiments/bench/gpu_check.sh FUZZ RENDER_BENCH OUT [LAVAPIPE_RECORDS]
#
# FUZZ is a paracosm-fuzz binary, RENDER_BENCH the criterion binary of
# `cargo bench -p paracosm-engine --bench render` (`cargo bench --no-run` prints its path),
# OUT a folder for the log and the results, LAVAPIPE_RECORDS an optional folder written by
# `camera_loop.py --save` on a machine without a GPU: the GPU's results are compared with it.
# RENDER_TESTS, when set, names the test binary of `cargo test -p paracosm-engine --test
# render` (golden images, bit-for-bit regions), run on the same adapter first.
# Nothing here selects the adapter: the renderer takes the highest-performance one it finds.
set -u
fuzz=$1 bench=$2 out=$3 records=${4:-}
mkdir -p "$out" "${XDG_RUNTIME_DIR:=/tmp/xdg}"
export XDG_RUNTIME_DIR
log() { echo "== $*"; }
TIMEFORMAT='wall %R s, user %U s, system %S s' 

log "machine: $(nproc) cores; $(nvidia-smi -L 2>/dev/null || echo 'no nvidia-smi')"
log "load average: $(cat /proc/loadavg)"
t=$(mktemp -d)
log "adapter with no flag"
probe() { "$fuzz" pedestrian-crossing --sut vision --budget 2 --jobs 1 --out "$t/probe" --force 2>&1; }
first=$(probe); echo "$first"
icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
if ! grep -q 'camera renderer: .*NVIDIA' <<<"$first" && [ -e "$icd" ]; then
    log "the loader's default search found no NVIDIA adapter; naming the driver's ICD file"
    export VK_DRIVER_FILES=$icd
    export __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
    second=$(probe); echo "$second"
    grep -q 'camera renderer: .*NVIDIA' <<<"$second" || unset VK_DRIVER_FILES __EGL_VENDOR_LIBRARY_FILENAMES
fi

if [ -n "${RENDER_TESTS:-}" ]; then
    log "the renderer's tests (engine/tests/render.rs) on this adapter"
    timeout 120 "$RENDER_TESTS" 2>&1 | grep -E '^test |adapter|panicked|left|right|result' | head -60
fi

log "render throughput, 320 x 240 colour + depth (criterion, frames/s as elem/s)"
timeout 150 "$bench" --bench --warm-up-time 1 --measurement-time 4 2>&1 \
    | grep -E '^(adapter|render_)|thrpt|time:' || log "render bench failed or timed out"

log "pedestrian study, one worker, CPU and wall per test"
timeout 240 python3 experiments/bench/camera_loop.py --bin "$fuzz" --runs 3 --budget 40 \
    --save "$out/gpu-records" ${records:+--compare "$records"} 2>&1

for sut in vision pilotnet; do
    log "throughput with every core: 1600 tests, --sut $sut, --jobs $(nproc)"
    time "$fuzz" pedestrian-crossing --strategy halton --budget 1600 --sut "$sut" \
        --out "$t/wide-$sut" --force 2>&1 | grep -v '^files:'
done

log "dataset export, 30 tests at 10 Hz, one worker, then every core (to /dev/shm: no disk)"
for jobs in 1 "$(nproc)"; do
    d=/dev/shm/paracosm-dataset-$jobs
    time "$fuzz" dataset pedestrian-crossing --strategy halton --budget 30 --rate 10 \
        --jobs "$jobs" --out "$d" --force 2>&1 | tail -3
    log "frames written with --jobs $jobs: $(find "$d" -name '*.png' | wc -l) PNG files"
    rm -rf "$d"
done
(cd "$out" && tar czf gpu-records.tgz gpu-records && rm -rf gpu-records)
rm -rf "$t"
