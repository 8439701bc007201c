#!/usr/bin/env bash
# Runs on a lent GPU machine, in one call: the GPU targets of issue 16 (scripts/gpu_frames.sh),
# the accuracy of the GPU backends on every hard-* scene against cpu, and the hard-* scenes'
# artifact pixels in the GPU pipeline and the host pipeline on simd against the ray-traced
# reference. Needs what scripts/gpu_prepare.sh leaves here (.gpu/shadowvol, .gl/*.deb), carried.
#
#   FRAMES=20 scripts/gpu_device.sh        (writes to $OUT, or to ${OUT_DIR:-gpu-device})
#
# What comes back from $OUT: summary.md (every table), log.txt and gpu-device.tar.gz (each JSON
# report and image). A step that fails is marked in the log and the summary; the others still run.
set -uo pipefail
export PATH="$PATH:/usr/sbin:/sbin"
# A container has no XDG_RUNTIME_DIR; without one libwayland prints an error line per adapter probe.
if [ -z "${XDG_RUNTIME_DIR:-}" ]; then
  XDG_RUNTIME_DIR="$(mktemp -d)" && export XDG_RUNTIME_DIR
fi
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
out="${OUT:-${OUT_DIR:-gpu-device}}"
mkdir -p "$out"
out="$(cd "$out" && pwd)"
frames="${FRAMES:-20}"
exec > >(tee "$out/log.txt") 2>&1
bin="${SHADOWVOL_BIN:-$root/.gpu/shadowvol}"
if [ ! -x "$bin" ]; then
  echo "error: $bin is missing: run scripts/gpu_prepare.sh on the build machine and carry .gpu"
  exit 1
fi
echo "revision: $(cat .gpu/revision 2>/dev/null || git rev-parse HEAD 2>/dev/null || echo unknown)"
echo "host: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2-)"
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>/dev/null || echo "nvidia-smi: none"

# Loaders: the image may have no Vulkan or OpenCL loader; unpack Debian's where one is missing
# (never over one the image has).
for pair in 'libvulkan\.so\.1:libvulkan1' 'libOpenCL\.so\.1:ocl-icd-libopencl1'; do
  lib="${pair%%:*}" pkg="${pair#*:}"
  ldconfig -p | grep "$lib" >/dev/null && continue
  deb=$(ls .gl/"$pkg"_*.deb 2>/dev/null | head -n 1)
  if [ -n "$deb" ]; then
    dpkg -x "$deb" / && ldconfig && echo "unpacked $deb"
  else
    echo "warning: no ${lib//\\/} here and no .gl/${pkg}_*.deb to unpack"
  fi
done
nv_icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
if [ -z "${VK_DRIVER_FILES:-}" ] && [ -f "$nv_icd" ]; then
  export VK_DRIVER_FILES="$nv_icd"
fi
nv_egl=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
if [ -z "${__EGL_VENDOR_LIBRARY_FILENAMES:-}" ] && [ -f "$nv_egl" ]; then
  export __EGL_VENDOR_LIBRARY_FILENAMES="$nv_egl"
fi
if [ ! -e /etc/OpenCL/vendors/nvidia.icd ] && ldconfig -p | grep 'libnvidia-opencl\.so\.1' >/dev/null; then
  mkdir -p /etc/OpenCL/vendors && echo libnvidia-opencl.so.1 >/etc/OpenCL/vendors/nvidia.icd
fi
"$bin" backends

work="$(mktemp -d)"
summary="$out/summary.md"
: >"$summary"
failed=()
step() {
  local name="$1"
  shift
  echo "==> $name"
  local t0=$SECONDS
  if "$@"; then
    echo "==> $name: ok ($((SECONDS - t0)) s)"
  else
    echo "==> $name: FAILED ($((SECONDS - t0)) s)"
    echo "**$name failed** (see log.txt)" >>"$summary"
    failed+=("$name")
  fi
}

frames_step() {
  SHADOWVOL_BIN="$bin" scripts/gpu_frames.sh "$work/frames" "$frames" &&
    { echo "## Frames (exact, 1280x720, --frames $frames)"; echo; cat "$work/frames/summary.md"; echo; } >>"$summary"
}

accuracy_step() {
  local b ok=0
  for b in wgpu vulkan opencl; do
    "$bin" accuracy --backend "$b" --format json >"$work/accuracy-$b.json" || ok=1
  done
  python3 - "$work" >>"$summary" <<'PY' || return 1
import json, os, sys
print("## Accuracy on every hard-* scene against cpu (`accuracy --backend B`)\n")
print("| backend | mode | scenes | open vertices | signs != exact | != cpu same mode | uncertain |")
print("|---|---|---|---|---|---|---|")
for b in ("wgpu", "vulkan", "opencl"):
    p = os.path.join(sys.argv[1], f"accuracy-{b}.json")
    try:
        recs = json.load(open(p))["records"]
    except Exception as e:
        print(f"| {b} | - | error: {e} | | | | |")
        continue
    for m in ("original", "robust", "ordered", "exact"):
        rs = [r for r in recs if r["mode"] == m]
        s = lambda k: sum(r[k] for r in rs)
        print(f"| {b} | {m} | {len(rs)} | {s('open_vertices')} | {s('sign_diff_vs_exact')} | "
              f"{s('diff_vs_cpu_same_mode')} | {s('uncertain')} |")
print()
PY
  return $ok
}

hard_step() {
  S="$bin" SIZES=320x240 BACKENDS="simd gpu" scripts/hard_reference_table.sh "$work/hard.jsonl" &&
    python3 - "$work/hard.jsonl" >>"$summary" <<'PY'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
errors = [r for r in rows if r.get("error")]
print("## Hard scenes, 320x240, --backdrop, artifact pixels against the reference\n")
print("| mode | renders | errors | GPU pipeline: sum, worst (scene) | host simd: sum, worst (scene) | covered px |")
print("|---|---|---|---|---|---|")
for m in ("robust", "ordered", "exact"):
    ok = [r for r in rows if r["mode"] == m and not r.get("error")]
    cell = []
    for b in ("gpu", "simd"):
        rs = [r for r in ok if r["backend"] == b]
        if not rs:
            cell.append("-")
            continue
        w = max(rs, key=lambda r: r["artifacts"] or 0)
        worst = f"{w['artifacts']} ({w['scene']})" if w["artifacts"] else "0"
        cell.append(f"{sum(r['artifacts'] or 0 for r in rs)}, {worst}")
    cov = sum(r["covered"] or 0 for r in ok if r["backend"] == "gpu")
    err = sum(1 for r in errors if r["mode"] == m)
    print(f"| {m} | {len(ok)} | {err} | {cell[0]} | {cell[1]} | {cov} |")
print()
PY
}

step frames frames_step
step accuracy accuracy_step
step hard-scenes hard_step
tar czf "$out/gpu-device.tar.gz" -C "$work" . && rm -rf "$work"
echo
cat "$summary"
if [ ${#failed[@]} -gt 0 ]; then
  echo "failed steps: ${failed[*]}"
  exit 1
fi
