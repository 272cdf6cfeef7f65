#!/bin/bash
# Alternates Bevy's SSAO and deep-gbuffer's obscurance, round by round, on the same device,
# scene, camera, size and radius, and prints each round's milliseconds and their ratios.
# usage: peers/bevy-ssao/compare.sh cornell|engine WIDTH HEIGHT ROUNDS
# (from the repository root, after `cargo build --features cli` there and
# `cargo build --release` in peers/bevy-ssao; DEEP_GBUFFER and PEER override the binaries)
set -euo pipefail
SCENE=${1:?cornell or engine}; W=${2:?width}; H=${3:?height}; R=${4:?rounds}
DEEP_GBUFFER=${DEEP_GBUFFER:-target/debug/deep-gbuffer}
PEER=${PEER:-peers/bevy-ssao/target/release/bevy-ssao-peer}
case $SCENE in
  cornell)
    # builtin:cornell's camera is the peer's default; Bevy's fixed effect radius (0.5 x 1.457).
    PEER_SCENE=(fixtures/cornell/CornellBox-Original.obj)
    PEER_VIEW=()
    DG=(builtin:cornell --ao-radius 0.7285)
    ;;
  engine)
    # The file's camera (node 81: eye, a point along -z, +y of its matrix; 18.01 degrees), the
    # scene scaled by 1/512 for Bevy, so deep-gbuffer takes Bevy's radius times 512.
    PEER_SCENE=(fixtures/engine/2CylinderEngine.gltf)
    PEER_VIEW=(1005.99,766.32,953.35 381.3,297.8,328.7 -0.3313,0.8835,-0.3313 18.01 0.001953125)
    DG=(fixtures/engine/2CylinderEngine.gltf --ao-radius 373)
    ;;
  *) echo "unknown scene $SCENE (cornell, engine)" >&2; exit 2 ;;
esac
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-$(mktemp -d)}
json=$(mktemp)
ms() { # the obscurance passes' sum in a --timings file
  python3 -c "import json,sys;m={p['name']:p['ms'] for p in json.load(open(sys.argv[1]))['passes']};print('%.1f'%sum(v for k,v in m.items() if k=='pyramid' or k.startswith('ao')))" "$1"
}
echo "load before: $(uptime)"
for r in $(seq "$R"); do
  peer=$("$PEER" "${PEER_SCENE[@]}" "$W" "$H" 200 "${PEER_VIEW[@]}" 2>/dev/null | sed -n 's|^render/ssao/elapsed_gpu: median \([0-9.]*\) ms.*|\1|p')
  line="round $r: bevy ssao (18 taps) $peer ms"
  for cfg in "bitmask 32 taps (default):" "bitmask 18 taps, 3 slices:--ao-samples 18 --ao-slices 3" "sao 11 taps:--ao-estimator sao --ao-samples 11" "bitmask 18 taps, half resolution:--ao-samples 18 --ao-slices 3 --ao-downsample 2"; do
    name=${cfg%%:*}; args=${cfg#*:}
    # shellcheck disable=SC2086
    "$DEEP_GBUFFER" render "${DG[@]}" --size "${W}x${H}" --frames 16 $args --timings "$json" >/dev/null 2>&1
    t=$(ms "$json")
    line="$line | $name $t ms ($(python3 -c "print('%.2f'%($t/$peer))")x)"
  done
  echo "$line"
done
echo "load after: $(uptime)"
rm -f "$json"
