#!/usr/bin/env bash
# Every hard-* preset, --backdrop, both sizes, robust/ordered/exact, every backend (host
# pipeline) and the GPU pipeline; one JSON summary line per render.
# Usage: S=target/release/shadowvol scripts/hard_reference_table.sh [ROWS.jsonl] (SIZES and
# BACKENDS, space-separated, narrow the run; `gpu` is the GPU pipeline). docs/RESULTS.md
# ("The two raster findings, fixed") shows, per (scene, mode), the largest count over the
# host-pipeline backends and the GPU pipeline column.
S=${S:-target/release/shadowvol}
out=${1:-hard_reference_rows.jsonl}
: > "$out"
scenes=$($S scenes --format json 2>/dev/null | python3 -c "import json,sys; d=json.load(sys.stdin); print(' '.join(x['name'] if isinstance(x,dict) else x for x in (d['scenes'] if isinstance(d,dict) else d) if (x['name'] if isinstance(x,dict) else x).startswith('hard-')))")
for size in ${SIZES:-128x128 320x240}; do
  for sc in $scenes; do
    for m in robust ordered exact; do
      for b in ${BACKENDS:-cpu simd wgpu opencl vulkan gpu}; do
        if [ "$b" = gpu ]; then args=(--pipeline gpu); else args=(--pipeline host --backend "$b"); fi
        $S render "$sc" "${args[@]}" --mode $m --reference --backdrop --size $size --format json --out "${TMPDIR:-/tmp}/hard_reference.png" 2>/dev/null \
          | python3 -c "
import json,sys
d=json.load(sys.stdin)
print(json.dumps({'size':'$size','scene':'$sc','mode':'$m','backend':'$b','pipeline':d['pipeline'],
 'artifacts':d['artifact_pixels'],'boundary':d['boundary_pixels'],'undecidable':d['undecidable_pixels'],
 'covered':d['covered_pixels'],'shadow':d['shadow_pixels'],'ref_shadow':d['reference_shadow_pixels'],
 'reference_ms':d['timings'].get('reference_ms')}))" >> "$out" || echo "{\"size\":\"$size\",\"scene\":\"$sc\",\"mode\":\"$m\",\"backend\":\"$b\",\"error\":true}" >> "$out"
      done
    done
  done
done
