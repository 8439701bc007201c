#!/usr/bin/env bash
# Digests of the images every hard-* preset renders to, on both pipelines and in every mode, so
# that a change to the renderer can be shown to leave the images byte-identical: run it with the
# binary before and after the change and diff the two files.
#
#   scripts/render_digests.sh BIN OUT_FILE [SIZE]      (SIZE defaults to 256x256)
#
# Each line: preset, pipeline, mode, plain or --backdrop (a receiver behind the scene, so that
# the shadows show), the PNG's sha256, then the JSON's counts that do not depend on timing
# (shadow_pixels, artifact_pixels, uncertain, the plan's techniques and side quads).
set -euo pipefail
bin="$1"
out="$2"
size="${3:-256x256}"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
: >"$out"
for scene in $("$bin" scenes --format json | python3 -c \
  'import json,sys; print(" ".join(s["name"] for s in json.load(sys.stdin) if s["name"].startswith("hard-")))'); do
  for pipeline in gpu host; do
    for mode in original robust ordered exact; do
     for extra in "" --backdrop; do
      png="$tmp/$scene-$pipeline-$mode.png"
      json="$("$bin" render "$scene" --pipeline "$pipeline" --mode "$mode" --size "$size" \
        --reference --out "$png" --format json $extra 2>/dev/null)"
      digest="$(sha256sum "$png" | cut -c1-16)"
      counts="$(python3 -c '
import json, sys
r = json.loads(sys.argv[1])
plan = ",".join("%s:%s" % (e["technique"], e["side_quads"]) for e in r["plan"])
print(r["shadow_pixels"], r["artifact_pixels"], r["uncertain"], plan)' "$json")"
      echo "$scene $pipeline $mode ${extra:-plain} $digest $counts" >>"$out"
     done
    done
  done
done
echo "$(wc -l <"$out") renders digested into $out"
