#!/usr/bin/env bash
# Artifact counts of every hard-* preset (--backdrop), each volume mode on the GPU pipeline and
# Bevy's default shadow map, one JSON line per render, for comparing two binaries (before and
# after a change to the reference's metric):
#   S=BIN scripts/footprint_counts.sh OUT.jsonl [SIZE (320x240)]
# footprint_boundary_pixels is null for a binary that predates it.
set -u
S=${S:-target/release/shadowvol}
out=$1
size=${2:-320x240}
: >"$out"
png="${TMPDIR:-/tmp}/footprint_counts_$$.png"
scenes=$("$S" scenes --format json | python3 -c \
  'import json,sys; print(" ".join(s["name"] for s in json.load(sys.stdin) if s["name"].startswith("hard-")))')
for sc in $scenes; do
  for m in original robust ordered exact map; do
    if [ "$m" = map ]; then args=(--shadows map); else args=(--mode "$m"); fi
    "$S" render "$sc" "${args[@]}" --backdrop --reference --size "$size" --out "$png" \
      --format json 2>/dev/null | python3 -c "
import json,sys
d=json.load(sys.stdin)
print(json.dumps({'scene':'$sc','mode':'$m','size':'$size','artifacts':d['artifact_pixels'],
 'footprint':d.get('footprint_boundary_pixels'),'boundary':d['boundary_pixels'],
 'geometric':d['geometric_artifact_pixels'],
 'geometric_footprint':d.get('geometric_footprint_boundary_pixels'),
 'ref_shadow':d['reference_shadow_pixels'],'reference_ms':d['timings'].get('reference_ms')}))" \
      >>"$out" || echo "{\"scene\":\"$sc\",\"mode\":\"$m\",\"error\":true}" >>"$out"
  done
done
rm -f "$png"
