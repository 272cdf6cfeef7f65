#!/usr/bin/env bash
# One markdown report of the raster and frame benchmarks, for a real GPU: the compute raster
# against the hardware rasterizer (Cornell box, 2CylinderEngine) and every pass of a full frame
# (Cornell box, grid-100000), at 1920x1080 and 3840x2160, each table headed by the device and the
# machine's load. Short criterion runs keep the whole report within a few minutes on a GPU.
#
#   scripts/gpu-report.sh [REPORT.md]
#
# Environment:
#   BENCH_DIR                   run prebuilt bench binaries (`raster-*`, `frame-*`) from this
#                               folder instead of `cargo bench` (a machine without Rust; see
#                               ../shared/GPU.md or the README's benchmark section)
#   DEEP_GBUFFER_REPORT_SIZES   image sizes (default 1920x1080,3840x2160)
#   DEEP_GBUFFER_REPORT_PROFILE cargo profile for `cargo bench` (default: bench; `dev` reuses the
#                               test build, GPU time does not depend on it)
set -euo pipefail
cd "$(dirname "$0")/.."
report=${1:-gpu-report.md}
sizes=${DEEP_GBUFFER_REPORT_SIZES:-1920x1080,3840x2160}
criterion=(--warm-up-time 1 --measurement-time 3 --sample-size 10)

# bench NAME VAR=VALUE...: runs one bench with the given environment, printing its output.
bench() {
    local name=$1
    shift
    if [ -n "${BENCH_DIR:-}" ]; then
        local binary
        binary=$(find "$BENCH_DIR" -maxdepth 1 -type f -name "$name-*" -perm -u+x | head -n 1)
        if [ -z "$binary" ]; then
            echo "no $name-* bench binary in $BENCH_DIR" >&2
            exit 1
        fi
        env "$@" "$binary" --bench "${criterion[@]}"
    else
        local profile=()
        if [ -n "${DEEP_GBUFFER_REPORT_PROFILE:-}" ]; then
            profile=(--profile "$DEEP_GBUFFER_REPORT_PROFILE")
        fi
        env "$@" cargo bench "${profile[@]}" --bench "$name" -- "${criterion[@]}"
    fi
}

# The summary the benches print after criterion's own lines (from its "Device:" line on).
tables() {
    sed -n '/^Device:/,$p'
}

started=$(date -u +%Y-%m-%dT%H:%MZ)
raster=$(bench raster DEEP_GBUFFER_BENCH_SIZES="$sizes" DEEP_GBUFFER_BENCH_SCENES=cornell,engine | tables)
frame=$(bench frame DEEP_GBUFFER_BENCH_GROUPS=passes DEEP_GBUFFER_BENCH_SIZES="$sizes" \
    DEEP_GBUFFER_BENCH_SCENES=cornell,grid-100000 | tables)
{
    echo "# deep-gbuffer GPU report"
    echo
    echo "Commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown), started $started, sizes $sizes."
    echo
    echo "## Compute raster against the hardware rasterizer"
    echo
    echo "$raster"
    echo
    echo "## Every pass of a frame"
    echo
    echo "$frame"
} > "$report"
echo "wrote $report"
