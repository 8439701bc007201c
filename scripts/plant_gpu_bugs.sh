#!/usr/bin/env bash
# Plants GPU-side bugs by hand, one at a time, in a scratch copy of the working tree, and checks
# that each one makes at least one test fail (the tests CI runs, with CI=true, on the drivers of
# this machine: lavapipe for wgpu and vulkan, PoCL for opencl).
#
#   scripts/plant_gpu_bugs.sh [SCRATCH_DIR]      (default: ${TMPDIR:-/tmp}/shadowvol-plant)
#
# Each mutant is one literal text replacement in a kernel source (WGSL, OpenCL C, GLSL; GLSL is
# recompiled to SPIR-V in the scratch copy, as `cargo xtask shaders` does). The script
# prints one line per mutant: KILLED (with the failing tests) or SURVIVED, and exits non-zero if
# any mutant survived or could not be planted. The working tree itself is never modified.
# CARGO_TARGET_DIR is honoured (a shared target dir keeps the registry dependencies built).
set -euo pipefail

root="$(cd "$(dirname "$0")/.." && pwd)"
scratch="${1:-${TMPDIR:-/tmp}/shadowvol-plant}"
export CI=true

# The source file of the crate that embeds each kernel (include_str!/include_bytes!). Cargo
# records a file outside the package by its absolute path, so a kernel planted in the scratch copy
# would not be seen as changed: touching the embedding file rebuilds the crate.
embedder() {
  case "$1" in
    shaders/resident_*.wgsl | shaders/render_*.wgsl) echo crates/renderer/src/resident/mod.rs ;;
    shaders/viewer_*.wgsl) echo crates/viewer/src/shaders.rs ;;
    shaders/*.wgsl) echo crates/wgpu-compute/src/shaders.rs ;;
    kernels/*.cl) echo crates/opencl/src/pipeline.rs ;;
    shaders/*.geom) echo crates/vulkan-geometry/src/pipeline.rs ;;
    *.rs) echo "$1" ;;
  esac
}

# One mutant per line, tab-separated: name, file, original text, planted text, test targets.
mutants="$(cat <<'LIST'
wgsl-sign-negated	shaders/silhouette.wgsl	return vec2<i32>(s0, 0);	return vec2<i32>(-s0, 0);	conformance gpu_lavapipe
wgsl-parity-dropped	shaders/silhouette.wgsl	m += select(s, -s, (ot & NEGATIVE) != 0u);	m += s;	conformance gpu_lavapipe resident
wgsl-robust-rule-dropped	shaders/silhouette.wgsl	if s0 != s1 || s1 != s2 {	if false {	conformance gpu_lavapipe
wgsl-f32-bound-shrunk	shaders/silhouette.wgsl	const F32_FILTER_EPS: f32 = 0x1p-19f;	const F32_FILTER_EPS: f32 = 0x1p-40f;	conformance gpu_lavapipe
wgsl-device-exact-dropped	shaders/silhouette.wgsl	return vec2<i32>(device_exact(p0, p1, l, p2), 1);	return vec2<i32>(UNCERTAIN, 1);	gpu_lavapipe
wgsl-uncertain-light-dropped	shaders/silhouette.wgsl	uncertain[slot] = Uncertain(t, li, 0u, 0u);	uncertain[slot] = Uncertain(t, 0u, 0u, 0u);	gpu_lavapipe
wgsl-f64-bound-shrunk	shaders/exact_f64.wgsl	const GPU_F64_FILTER_EPS: f64 = 8e-15lf;	const GPU_F64_FILTER_EPS: f64 = 1e-30lf;	conformance gpu_lavapipe
opencl-sign-negated	kernels/silhouette.cl	s *= parity;	s *= -parity;	conformance device
opencl-robust-rule-dropped	kernels/silhouette.cl	s = (s0 == s1 && s1 == s2) ? s0 : 0;	s = s0;	conformance device
opencl-f32-bound-shrunk	kernels/silhouette.cl	#define SV_F32_FILTER_EPS 0x1.0p-19f	#define SV_F32_FILTER_EPS 0x1.0p-40f	conformance device
opencl-f64-bound-shrunk	kernels/silhouette.cl	double bound = 1.0e-15 * perm;	double bound = 1.0e-30 * perm;	conformance device
glsl-sign-negated	shaders/silhouette_gs.geom	s = t * parity;	s = -t * parity;	conformance
glsl-robust-rule-dropped	shaders/silhouette_gs.geom	if (t != t1 || t1 != t2) {	if (false) {	conformance
glsl-f32-bound-shrunk	shaders/silhouette_gs.geom	precise float bound = 1.9073486328125e-06 * perm;	precise float bound = 1.0e-12 * perm;	conformance
glsl-f64-bound-shrunk	shaders/silhouette_gs.geom	precise double bound = 1.0e-15LF * perm;	precise double bound = 1.0e-30LF * perm;	conformance
resident-touch-ignored	shaders/resident_extract.wgsl	return l.w != 0.0 && exact_product_is(p.x	return false && exact_product_is(p.x	resident
resident-touch-rounded	shaders/resident_extract.wgsl	fn exact_product_is(p: f32, w: f32, l: f32) -> bool {	fn exact_product_is(p: f32, w: f32, l: f32) -> bool { return p * w == l;	resident
resident-extrude-lo-dropped	shaders/resident_draw.wgsl	d = (p - a.xyz) - r_light_points[k + 1u].xyz;	d = p - a.xyz;	resident
resident-side-flipped	shaders/resident_draw.wgsl	if (record & R_NEGATIVE) != 0u {	if (record & R_NEGATIVE) == 0u {	resident
resident-back-cap-flipped	shaders/resident_draw.wgsl	if s == 1 && c != 0u {	if s == -1 && c != 0u {	resident
resident-zfail-list-from-front	shaders/resident_draw.wgsl	return side_vertex(r_records[lt.draw.x + lt.draw.y - 1u - i], v);	return side_vertex(r_records[lt.draw.x + i], v);	resident
twin-robust-rule	crates/wgpu-compute/src/twin.rs	if s0 == s1 && s1 == s2 { s0 } else { 0 }	if true { s0 } else { 0 }	twin resident
integer-path-zero	crates/wgpu-compute/src/shaders.rs	return orient_int(a, b, l, o); // @exact-int"	return 0; // @exact-int"	gpu_lavapipe resident
resident-pending-never-dispatched	shaders/resident_extract.wgsl	pending_dispatch[0] = select(0u, x, any);	pending_dispatch[0] = 0u;	resident
resident-pending-sign-dropped	shaders/resident_extract.wgsl	signs[k] = s;	signs[k] = 0;	resident
resident-touch-skip-dropped	crates/renderer/src/resident/pipeline.rs	(shaders::TOUCH_SIGNS_CONSTANT, 1.0),	(shaders::TOUCH_SIGNS_CONSTANT, 0.0),	resident
resident-chunk-offset-dropped	shaders/resident_draw.wgsl	let t = r_chunk.first + k;	let t = k;	resident
wgsl-resolve-sign-dropped	shaders/silhouette.wgsl	signs[r.light * params.tri_count + r.triangle] = s;	signs[r.light * params.tri_count + r.triangle] = 0;	gpu_lavapipe
wgsl-table-offset-shifted	shaders/silhouette.wgsl	return tables[table_at.tris + 3u * t + r];	return tables[table_at.tris + 3u * t + r + 3u];	default_limits gpu_lavapipe resident
dispatch-inline-fallback-dropped	crates/wgpu-compute/src/dispatch.rs	if steps.deferred.is_none() {	if true {	gpu_lavapipe
twin-resolve-skipped	crates/wgpu-compute/src/twin.rs	for r in &out.uncertain {	for r in out.uncertain.iter().take(0) {	twin
LIST
)"

echo "scratch copy: $scratch"
rm -rf "$scratch"
mkdir -p "$scratch"
tar -C "$root" --exclude=./target --exclude=./.git --exclude=./fuzz/target -cf - . | tar -C "$scratch" -xf -
cd "$scratch"

# The unplanted copy must pass the same tests, or a kill would mean nothing.
if ! cargo test --workspace --test conformance --test gpu_lavapipe --test device --test resident --test twin \
  >"$scratch/plant-baseline.log" 2>&1; then
  echo "baseline: the unplanted copy fails its tests; see $scratch/plant-baseline.log"
  exit 2
fi
echo "baseline: the unplanted copy passes"

only="${PLANT_ONLY:-}"   # optional: an extended regex over the mutant names to run
survived=0
while IFS=$'\t' read -r name file from to tests; do
  [ -n "$only" ] && ! [[ "$name" =~ $only ]] && continue
  cp "$root/$file" "$file"
  count=$(grep -cF -- "$from" "$file" || true)
  if [ "$count" -ne 1 ]; then
    echo "$name: CANNOT PLANT: '$from' occurs $count times in $file (expected once)"
    survived=$((survived + 1))
    continue
  fi
  FROM="$from" TO="$to" perl -0pi -e 's/\Q$ENV{FROM}\E/$ENV{TO}/' "$file"
  touch "$(embedder "$file")"
  if [[ "$file" == *.geom ]]; then
    # What `cargo xtask shaders` does for this source (not run here: a shared xtask binary
    # would write into the working tree it was built from).
    g() { glslangValidator -V --target-env vulkan1.1 "$@" shaders/silhouette_gs.geom >/dev/null; }
    g -o shaders/silhouette_gs.geom.spv
    g -DSHADOWVOL_NO_F64 -o shaders/silhouette_gs.f32.geom.spv
  fi
  args=()
  for t in $tests; do args+=(--test "$t"); done
  log="$scratch/plant-$name.log"
  if cargo test --workspace --no-fail-fast "${args[@]}" >"$log" 2>&1; then
    echo "$name: SURVIVED ($file: '$from' -> '$to'; tests: $tests)"
    survived=$((survived + 1))
  else
    failed=$(grep -E '^test .* FAILED$' "$log" | sed -E 's/^test //; s/ +\.\.\. FAILED$//' | head -3 | tr '\n' ' ')
    nfail=$(grep -cE '^test .* FAILED$' "$log" || true)
    if [ "$nfail" -eq 0 ]; then
      echo "$name: ERROR (no test failed, but cargo did; see $log)"
      survived=$((survived + 1))
    else
      # Failing tests per test binary ("conformance.rs" is the cross-backend suite, tests/*.rs
      # the crates' own).
      per=$(awk '/^     Running /{bin=$2} /^test .* FAILED$/{n[bin]++} END{for (b in n) printf "%s %d, ", b, n[b]}' "$log")
      echo "$name: KILLED ($nfail failing tests: ${per%, }; e.g. $failed)"
    fi
  fi
  # Restore the file (and the SPIR-V) before the next mutant.
  cp "$root/$file" "$file"
  if [[ "$file" == *.geom ]]; then
    cp "$root"/shaders/*.spv shaders/
  fi
  touch "$(embedder "$file")"
done <<<"$mutants"

# The scratch copy shares artifacts with the working tree (same target dir, same metadata):
# rebuild them from the restored sources before leaving.
cargo test --workspace --test conformance --test gpu_lavapipe --test device --no-run >/dev/null 2>&1
[ "$survived" -eq 0 ]
