#!/usr/bin/env bash
# The non-zero artifact counts of docs/MAPS.md's per-scene table, rendered again at its size
# (1280x720, --backdrop for hard-*, no --frames: the counts are the first frame's), one JSON
# line each, for comparing two binaries (before and after a change to the reference's metric).
# A count of 0 cannot grow under a rule that only moves pixels out of the artifact count.
#   S=BIN scripts/footprint_maps.sh OUT.jsonl
set -u
S=${S:-target/release/shadowvol}
out=$1
: >"$out"
png="${TMPDIR:-/tmp}/footprint_maps_$$.png"
while read -r scene label args; do
  [ -z "$scene" ] && continue
  extra=()
  case "$scene" in hard-*) extra=(--backdrop) ;; esac
  # shellcheck disable=SC2086
  "$S" render "$scene" $args "${extra[@]}" --reference --size 1280x720 --out "$png" \
    --format json 2>/dev/null | python3 -c "
import json,sys
d=json.load(sys.stdin)
print(json.dumps({'scene':'$scene','config':'$label','artifacts':d['artifact_pixels'],
 'footprint':d.get('footprint_boundary_pixels'),'boundary':d['boundary_pixels'],
 'reference_ms':d['timings'].get('reference_ms')}))" >>"$out" \
    || echo "{\"scene\":\"$scene\",\"config\":\"$label\",\"error\":true}" >>"$out"
done <<'LIST'
hard-edge-on-tilted-fan original --pipeline gpu --mode original
hard-edge-on-tilted-fan robust --pipeline gpu --mode robust
hard-double-sided-sheet original --pipeline gpu --mode original
hard-directional-parallel original --pipeline gpu --mode original
hard-multi-object-transforms original --pipeline gpu --mode original
hard-homogeneous-w original --pipeline gpu --mode original
hard-homogeneous-w robust --pipeline gpu --mode robust
hard-homogeneous-w ordered --pipeline gpu --mode ordered
hard-welded-duplicates original --pipeline gpu --mode original
hard-welded-duplicates robust --pipeline gpu --mode robust
hard-welded-duplicates ordered --pipeline gpu --mode ordered
hard-welded-duplicates exact --pipeline gpu --mode exact
hard-welded-duplicates host-exact --pipeline host --backend cpu --mode exact
hard-edge-on-tilted-fan map-2048-pcf-default --shadows map --map-size 2048 --map-filter pcf
hard-light-at-vertex map-2048-pcf-default --shadows map --map-size 2048 --map-filter pcf
hard-offset-1e4-sphere map-2048-pcf-default --shadows map --map-size 2048 --map-filter pcf
hard-offset-1e4-tilted-grid map-2048-pcf-default --shadows map --map-size 2048 --map-filter pcf
hard-book-4 map-2048-pcf-default --shadows map --map-size 2048 --map-filter pcf
hard-book-5 map-2048-pcf-default --shadows map --map-size 2048 --map-filter pcf
hard-double-sided-sheet map-2048-pcf-default --shadows map --map-size 2048 --map-filter pcf
hard-welded-duplicates map-2048-pcf-default --shadows map --map-size 2048 --map-filter pcf
hard-soup-near-light map-2048-pcf-default --shadows map --map-size 2048 --map-filter pcf
hard-directional-parallel map-2048-pcf-default --shadows map --map-size 2048 --map-filter pcf
hard-multi-object-transforms map-2048-pcf-default --shadows map --map-size 2048 --map-filter pcf
hard-homogeneous-w map-2048-pcf-default --shadows map --map-size 2048 --map-filter pcf
bunnies-10-individual map-2048-pcf-default --shadows map --map-size 2048 --map-filter pcf
hard-edge-on-tilted-fan map-512-hard-0.3,0,1.8 --shadows map --map-size 512 --map-filter hard --map-bias 0.3,0,1.8
hard-homogeneous-w map-8192-pcf-0.005,0,0.3 --shadows map --map-size 8192 --map-filter pcf --map-bias 0.005,0,0.3
hard-double-sided-sheet map-4096-pcf-0.005,0,0.3 --shadows map --map-size 4096 --map-filter pcf --map-bias 0.005,0,0.3
hard-soup-near-light map-4096-pcf-0.005,0,0.3 --shadows map --map-size 4096 --map-filter pcf --map-bias 0.005,0,0.3
hard-light-at-vertex map-2048-pcf-0.005,0,0.3 --shadows map --map-size 2048 --map-filter pcf --map-bias 0.005,0,0.3
hard-multi-object-transforms map-8192-hard-0.02,0,0.6 --shadows map --map-size 8192 --map-filter hard --map-bias 0.02,0,0.6
hard-offset-1e4-sphere map-4096-pcf-0.005,0,0.3 --shadows map --map-size 4096 --map-filter pcf --map-bias 0.005,0,0.3
bunnies-10-individual map-8192-pcf-0.005,0,0.3 --shadows map --map-size 8192 --map-filter pcf --map-bias 0.005,0,0.3
LIST
rm -f "$png"
