#!/usr/bin/env bash
# The GPU pipeline against the host pipeline and against shadow maps on a real GPU, in one run
# (for a session that is lent a device machine; see docs/GPU.md). Builds the release CLI, then
# for each scene renders --frames N with the GPU pipeline, the host pipeline on simd, the host
# pipeline on wgpu, and shadow maps (Bevy's defaults, and 8192 texels), back to back, and
# writes one JSON report per run plus a summary table. Then times the `wgpu`
# silhouette backend alone on sphere-1m in every mode (`bench`), which shows what exact mode's
# certified filter and its integer dispatch cost on the device.
#
#   scripts/gpu_frames.sh [OUT_DIR] [FRAMES]      (defaults: ${OUT:-gpu-frames}, 20)
#
# SHADOWVOL_BIN=PATH runs that binary instead of building one (a lent machine has no cargo:
# scripts/gpu_prepare.sh builds it here and scripts/gpu_device.sh runs this script there).
set -euo pipefail
out="${1:-${OUT:-gpu-frames}}"
frames="${2:-20}"
root="$(cd "$(dirname "$0")/.." && pwd)"
mkdir -p "$out"
out="$(cd "$out" && pwd)"
cd "$root"
if [ -n "${SHADOWVOL_BIN:-}" ]; then
  bin="$SHADOWVOL_BIN"
else
  cargo build --release -p shadowvol
  bin="${CARGO_TARGET_DIR:-$root/target}/release/shadowvol"
fi
"$bin" backends --format json >"$out/backends.json"
summary="$out/summary.md"
echo "| scene | run | median ms | p10 | p90 | read back | extract | sides | caps | shadow maps | lighting |" >"$summary"
echo "|---|---|---|---|---|---|---|---|---|---|---|" >>"$summary"
for scene in sphere-1m spheres-100x1k sphere-100k town; do
  for run in gpu host-simd host-wgpu map-bevy map-8192; do
    case $run in
      gpu) args=(--pipeline gpu) ;;
      host-simd) args=(--pipeline host --backend simd) ;;
      host-wgpu) args=(--pipeline host --backend wgpu) ;;
      map-bevy) args=(--shadows map) ;;
      map-8192) args=(--shadows map --map-size 8192) ;;
    esac
    json="$out/$scene-$run.json"
    "$bin" render "$scene" --size 1280x720 --mode exact --frames "$frames" "${args[@]}" \
      --out "$out/$scene-$run.png" --format json >"$json"
    python3 - "$json" "$scene" "$run" >>"$summary" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
f, g = d["frames"], d["gpu_timings_ms"] or {}
cell = lambda k: f"{g[k]:.2f}" if k in g else "-"
print(f"| {sys.argv[2]} | {sys.argv[3]} | {f['median_ms']:.2f} | {f['p10_ms']:.2f} | "
      f"{f['p90_ms']:.2f} | {d['frame_readback_bytes']} | {cell('extract')} | "
      f"{cell('sides')} | {cell('caps')} | {cell('shadow_maps')} | {cell('lighting')} |")
PY
  done
done
echo >>"$summary"
echo "| bench sphere-1m, wgpu | median ms | p10 | p90 | compute ms | uncertain |" >>"$summary"
echo "|---|---|---|---|---|---|" >>"$summary"
"$bin" bench --scene sphere-1m --backend wgpu --mode original,robust,ordered,exact \
  --frames "$((frames * 5))" --format json >"$out/bench-wgpu.json"
python3 - "$out/bench-wgpu.json" >>"$summary" <<'PY'
import json, sys
for r in json.load(open(sys.argv[1]))["records"]:
    print(f"| {r['mode']} | {r['median_ms']:.3f} | {r['p10_ms']:.3f} | {r['p90_ms']:.3f} | "
          f"{r['compute_ms']:.3f} | {r['uncertain']} |")
PY
cat "$summary"
