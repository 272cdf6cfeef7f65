#!/bin/bash
# Alternates Bevy's SSAO and deep-gbuffer's obscurance on the Cornell box, round by round, on
# the same device, size and radius, and prints each round's milliseconds and their ratio.
# usage: peers/bevy-ssao/compare.sh WIDTH HEIGHT ROUNDS
# (from the repository root, after `cargo build --features cli` there and
# `cargo build --release` in peers/bevy-ssao; DEEP_GBUFFER and PEER override the binaries)
set -euo pipefail
W=${1:?width}; H=${2:?height}; R=${3:?rounds}
DEEP_GBUFFER=${DEEP_GBUFFER:-target/debug/deep-gbuffer}
PEER=${PEER:-peers/bevy-ssao/target/release/bevy-ssao-peer}
OBJ=fixtures/cornell/CornellBox-Original.obj
# Bevy's fixed effect radius (0.5 x 1.457 world units), given to deep-gbuffer too.
RADIUS=0.7285
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-$(mktemp -d)}
json=$(mktemp)
ms() { # the obscurance passes' sum in a --timings file
  python3 -c "import json,sys;m={p['name']:p['ms'] for p in json.load(open(sys.argv[1]))['passes']};print('%.1f'%sum(v for k,v in m.items() if k=='pyramid' or k.startswith('ao')))" "$1"
}
echo "load before: $(uptime)"
for r in $(seq "$R"); do
  peer=$("$PEER" "$OBJ" "$W" "$H" 200 2>/dev/null | sed -n 's|^render/ssao/elapsed_gpu: median \([0-9.]*\) ms.*|\1|p')
  line="round $r: bevy ssao (18 taps) $peer ms"
  for cfg in "bitmask 32 taps (default):" "bitmask 18 taps, 3 slices:--ao-samples 18 --ao-slices 3" "sao 11 taps:--ao-estimator sao --ao-samples 11" "bitmask 18 taps, half resolution:--ao-samples 18 --ao-slices 3 --ao-downsample 2"; do
    name=${cfg%%:*}; args=${cfg#*:}
    # shellcheck disable=SC2086
    "$DEEP_GBUFFER" render builtin:cornell --size "${W}x${H}" --frames 16 --ao-radius $RADIUS $args --timings "$json" >/dev/null 2>&1
    t=$(ms "$json")
    line="$line | $name $t ms ($(python3 -c "print('%.2f'%($t/$peer))")x)"
  done
  echo "$line"
done
echo "load after: $(uptime)"
rm -f "$json"
