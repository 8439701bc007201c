#!/usr/bin/env bash
# Run here before a lent GPU machine's call (see docs/GPU.md, "Measuring on a GPU machine"). That
# machine has neither cargo nor a network, so this builds the release CLI and strips it into
# .gpu/shadowvol, fetches Debian's Vulkan and OpenCL loaders into .gl/, checks that the working
# tree and both folders fit what one call carries (64 MiB), and prints the call to make.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
cargo build --release -p shadowvol
mkdir -p .gpu .gl
cp "${CARGO_TARGET_DIR:-$root/target}/release/shadowvol" .gpu/shadowvol
strip .gpu/shadowvol
if [ -n "$(git status --porcelain --untracked-files=no)" ]; then
  echo "$(git rev-parse HEAD) with uncommitted changes" >.gpu/revision
else
  git rev-parse HEAD >.gpu/revision
fi
rm -f .gl/*.deb
if ! (cd .gl && apt-get download libvulkan1 ocl-icd-libopencl1); then
  echo "error: apt-get download failed; fetch libvulkan1 and ocl-icd-libopencl1 (amd64 .deb) into .gl/" >&2
  exit 1
fi
tree_bytes=$(git ls-files -z --cached --others --exclude-standard | xargs -0 du -cb 2>/dev/null | tail -1 | cut -f1)
carried=$(du -cb .gpu .gl | tail -1 | cut -f1)
total=$((tree_bytes + carried))
limit=$((64 * 1024 * 1024))
printf 'travels: working tree %d + .gpu/.gl %d = %d bytes (limit %d)\n' "$tree_bytes" "$carried" "$total" "$limit"
if [ "$total" -gt "$limit" ]; then
  echo "error: the call would carry more than 64 MiB" >&2
  exit 1
fi
cat <<'CALL'
Now, on the device tool (one call, about 3-5 minutes on an H100/H200 after its start):
  run  command: FRAMES=20 scripts/gpu_device.sh
       carry:   [".gpu", ".gl"]
       timeout_s: 480
Then give_back, and record $OUT's summary.md in docs/GPU.md.
CALL
