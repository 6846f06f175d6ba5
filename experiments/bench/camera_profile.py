#!/usr/bin/env python3
"""Where a camera test's CPU time goes: `perf record` of a pedestrian-study campaign for each
system under test, its samples sorted into the parts of a closed-loop test (the camera-loop
issue, requirement 1).

Runs `perf record -F 999` (software clock, every thread of the process: Mesa's JIT-compiled
shaders and lavapipe included) on
`paracosm-fuzz scenarios/pedestrian_crossing.star --strategy halton --budget B --jobs 1`
with `--sut aeb`, `vision`, `pilotnet` and an external process
(`python3 scenarios/benches/camera_sut.py`, whose own Python is not sampled: its share is the
rest of the wall time), then `perf report --no-children --sort dso,sym` and sorts each
symbol by the first rule of PARTS that matches its shared object and name. Prints one table,
shares of each campaign's samples in percent, and the campaign's CPU seconds (user + sys of
paracosm-fuzz alone).

    python3 experiments/bench/camera_profile.py --bin target/release/paracosm-fuzz [--budget 20]

Needs Linux `perf` (Debian: linux-perf) allowed to sample the process
(kernel.perf_event_paranoid ≤ 2).
"""

import argparse
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[2]
SUTS = {
    "aeb": ["--sut", "aeb"],
    "vision": ["--sut", "vision"],
    "pilotnet": ["--sut", "pilotnet"],
    "external": ["--sut-cmd", "python3 scenarios/benches/camera_sut.py"],
}
# (part, pattern on "shared-object symbol"), first match wins.
PARTS = [
    ("kernel", r"^\[kernel"),
    ("libc (copies, allocation, rounding)", r"^(libc|ld-linux|libm)[.-]"),
    ("render (Mesa: shaders, rasteriser, driver)",
     r"^(\[JIT\]|libvulkan_lvp|swrast_dri|libLLVM|libgallium|libEGL|libGL)|wgpu|naga"),
    ("readback (GPU buffer to frame)", r"paracosm_engine::render::gpu"),
    ("pixel noise", r"paracosm_engine::render::post|rand_chacha|rand_distr"),
    ("preprocessing (crop, resize, normalise)",
     r"paracosm_engine::sut::(onnx::Preprocessor|resample|onnx::preprocess)|image::imageops|"
     r"image::image::SubImage"),
    ("inference (tract)", r"tract|mmm_f32|ndarray"),
    ("perception (vision)", r"paracosm_engine::sut::vision"),
    ("external protocol", r"paracosm_engine::sut::external|Payload|serde_json::ser"),
    ("physics (rapier, vehicle, lidar, actors)",
     r"rapier3d|parry3d|paracosm_engine::(car|vehicle|sim|contact|network|pedestrian|ttc|"
     r"sensor::lidar|obstacle|actor|sut::aeb|sut::cruise)|nalgebra|simba"),
    ("reactive runtime and monitors",
     r"paracosm_engine::rx|starlark|paracosm_scenarios::(lang|runner|monitor)|paracosm_oracles"),
    ("recording and report (JSONL, plots, PNG)",
     r"serde_json|csv|png::|miniz_oxide|fdeflate|plotters|image::codecs|paracosm::report|"
     r"linfa|ttf_parser|ab_glyph|tiny_skia"),
]


def profile(binary, sut, budget, tmp):
    data = os.path.join(tmp, f"{sut}.data")
    out = os.path.join(tmp, f"out-{sut}")
    cmd = ["perf", "record", "-F", "999", "-o", data, "--", binary, "scenarios/pedestrian_crossing.star",
           "--strategy", "halton", "--budget", str(budget), "--jobs", "1", "--out", out, "--force",
           *SUTS[sut]]
    proc = subprocess.Popen(cmd, cwd=REPO_ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    if os.waitstatus_to_exitcode(status) not in (0, 1):
        sys.exit(f"{' '.join(cmd)} failed: {proc.stderr.read().decode(errors='replace')[-2000:]}")
    report = subprocess.run(
        ["perf", "report", "-i", data, "--no-children", "--sort", "dso,sym", "--stdio", "-q",
         "--percent-limit", "0"],
        check=True, capture_output=True, text=True).stdout
    shares = {name: 0.0 for name, _ in PARTS}
    shares["other"] = 0.0
    for line in report.splitlines():
        m = re.match(r"\s*([0-9.]+)%\s+(.+?)\s+\[.\]\s+(.*)$", line)
        if not m:
            continue
        share, dso, sym = float(m.group(1)), m.group(2).strip(), m.group(3)
        key = f"{dso} {sym}"
        for name, pattern in PARTS:
            if re.search(pattern, key):
                shares[name] += share
                break
        else:
            shares["other"] += share
    # The rusage is perf's and the campaign's together (perf's own share is small).
    return shares, usage.ru_utime + usage.ru_stime


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin", required=True, help="the paracosm-fuzz binary")
    ap.add_argument("--budget", type=int, default=20)
    ap.add_argument("--sut", action="append", choices=list(SUTS))
    args = ap.parse_args()
    suts = args.sut or list(SUTS)
    binary = str(Path(args.bin).resolve())
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for sut in suts:
            results[sut] = profile(binary, sut, args.budget, tmp)
    print(f"{binary}: pedestrian study, {args.budget} Halton tests, --jobs 1; shares of "
          f"perf samples, %")
    print("| part | " + " | ".join(suts) + " |")
    print("|---|" + "---:|" * len(suts))
    for name in [n for n, _ in PARTS] + ["other"]:
        print(f"| {name} | " + " | ".join(f"{results[s][0][name]:.1f}" for s in suts) + " |")
    print("| CPU-s of the campaign (perf included) | "
          + " | ".join(f"{results[s][1]:.2f}" for s in suts) + " |")


if __name__ == "__main__":
    main()
