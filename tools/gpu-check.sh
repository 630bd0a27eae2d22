#!/usr/bin/env bash
# Checks splitray on this machine's GPU with the bundle tools/gpu-bundle.sh made
# (.gpu-bundle/ in this checkout), where neither a Rust toolchain nor a Vulkan loader is
# installed. Parts, in order (default: all four):
#
#   info   `splitray info`: the devices, their queues and the streams' queues;
#   tests  every test of the library and of tests/suite, with the validation layer on
#          (any validation message fails its test), on the first device (SPLITRAY_DEVICE
#          chooses another);
#   bench  `splitray bench bdpt` on lamps, fixture and the Cornell box: lvc-bdpt and
#          cis-lbdpt at equal spp (512², 8 passes, median of 2 rounds) with 1 and 3
#          streams and material sorting on and off: times, per-stream busy time and
#          overlap, per-kernel GPU times;
#   mse    pt, lvc-bdpt and cis-lbdpt at equal time (4 s each, in 4 turns) on fixture and
#          lamps at 64²: relative MSE against 30-s lvc-bdpt references rendered first
#          with a seed of their own (the benchmark takes their own noise out).
#
#   tools/gpu-check.sh [RESULTS] [PART...]     # RESULTS defaults to gpu-results/
#
# Parts can run in several calls with the same RESULTS (`info tests`, then `bench mse`):
# the summary gathers them. GPU_CHECK_TESTS=PATTERN runs only the tests whose names
# contain it; GPU_CHECK_SIZE and GPU_CHECK_SPP set the equal-spp film side and passes,
# GPU_CHECK_REF_S and GPU_CHECK_MSE_S the seconds of each reference and contestant (on a
# CPU device, say).
#
# Each part writes its log (and the benchmarks their JSON) to RESULTS and a line to
# RESULTS/summary; the exit status is non-zero when a part failed. Nothing is installed:
# the packages are unpacked into a temporary folder and found through LD_LIBRARY_PATH and
# VK_LAYER_PATH. The tests were built with the checkout's path (BUILD_ROOT in the
# manifest) compiled in; where that path does not exist, it is made a link to this
# checkout.
set -uo pipefail
cd "$(dirname "$0")/.."
bundle=.gpu-bundle
results=${1:-gpu-results}
shift || true
if [[ $# -gt 0 ]]; then parts=("$@"); else parts=(info tests bench mse); fi
for part in "${parts[@]}"; do
    [[ $part =~ ^(info|tests|bench|mse)$ ]] ||
        { echo "$0: unknown part '$part' (info, tests, bench or mse)" >&2; exit 2; }
done
size=${GPU_CHECK_SIZE:-512}
spp=${GPU_CHECK_SPP:-8}
reference_s=${GPU_CHECK_REF_S:-30}
contestant_s=${GPU_CHECK_MSE_S:-4}
[[ -f $bundle/manifest ]] || { echo "$0: no $bundle/manifest: run tools/gpu-bundle.sh first" >&2; exit 2; }
# shellcheck source=/dev/null
source "$bundle/manifest"
mkdir -p "$results"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

unpack() { gunzip -c "$bundle/$1.gz" >"$work/$1" && chmod +x "$work/$1"; }
for name in splitray splitray-ci $TESTS; do
    unpack "$name" || { echo "$0: cannot unpack $bundle/$name.gz" >&2; exit 2; }
done
for deb in "$bundle"/debs/*.deb; do
    dpkg-deb -x "$deb" "$work/root" || { echo "$0: cannot unpack $deb" >&2; exit 2; }
done
export LD_LIBRARY_PATH="$work/root/usr/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
export VK_LAYER_PATH="$work/root/usr/share/vulkan/explicit_layer.d"
# The loader looks for drivers under /etc and /usr/share (and /usr/local/share); NVIDIA's
# container toolkit can leave its ICD file under /usr/local/nvidia instead.
if [[ -z ${VK_DRIVER_FILES:-}${VK_ICD_FILENAMES:-} ]] &&
    ! compgen -G '/usr/share/vulkan/icd.d/nvidia*.json' >/dev/null &&
    ! compgen -G '/etc/vulkan/icd.d/nvidia*.json' >/dev/null &&
    [[ -f /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ]]; then
    export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
fi

# The tests read the checkout and run the `ci` binary at BUILD_ROOT/target/ci/splitray.
here=$(pwd -P)
if [[ ! -e $BUILD_ROOT ]]; then
    mkdir -p "$(dirname "$BUILD_ROOT")" && ln -s "$here" "$BUILD_ROOT"
elif [[ $(cd "$BUILD_ROOT" && pwd -P) != "$here" ]]; then
    echo "$0: the tests were built in $BUILD_ROOT, which is another folder: run this in it" >&2
    exit 2
fi
# A binary that cargo built there is left alone; one from an older bundle is replaced.
ci_binary=$BUILD_ROOT/target/ci/splitray
stamp=$BUILD_ROOT/target/ci/.splitray-from-gpu-bundle
if [[ ! -e $ci_binary ]] || { [[ -f $stamp ]] && [[ $(cat "$stamp") != "$COMMIT $BUILT" ]]; }; then
    mkdir -p "$(dirname "$ci_binary")" && cp "$work/splitray-ci" "$ci_binary" &&
        echo "$COMMIT $BUILT" >"$stamp"
fi

# The equal-time comparison: references first, then the contestants in turns.
equal_time() {
    local scene
    for scene in fixture lamps; do
        "$work/splitray" render "$scene" --integrator lvc-bdpt --width 64 --height 64 \
            --time "$reference_s" --seed 977 -o "$work/reference-$scene.exr" || return
    done
    "$work/splitray" bench bdpt fixture lamps --integrators pt,lvc-bdpt,cis-lbdpt \
        --width 64 --height 64 --time "$contestant_s" --rounds 4 --spp 0 \
        --reference "$work/reference-fixture.exr" --reference "$work/reference-lamps.exr" \
        --json "$results/bench-mse.json"
}

echo "bundle of $COMMIT built $BUILT; checked $(date -u +%Y-%m-%dT%H:%M:%SZ) on $(hostname)" \
    | tee -a "$results/summary"
status=0
record() { # record PART RC SECONDS: a line of the summary
    local verdict=passed
    [[ $2 -eq 0 ]] || { verdict="FAILED (exit $2)"; status=1; }
    echo "$1: $verdict in $3 s" | tee -a "$results/summary"
}
for part in "${parts[@]}"; do
    start=$SECONDS
    case $part in
    info)
        "$work/splitray" info >"$results/info.log" 2>&1
        ;;
    tests)
        rc=0
        : >"$results/tests.log"
        # The live-view tests open windows on a virtual X display (Xvfb).
        skip=()
        command -v Xvfb >/dev/null || {
            skip=(--skip preview_window)
            echo "tests: no Xvfb: the preview_window tests are left out" | tee -a "$results/summary"
        }
        for t in $TESTS; do
            echo "== $t" >>"$results/tests.log"
            SPLITRAY_VALIDATION=1 "$work/$t" --test-threads "$(nproc)" "${skip[@]}" \
                ${GPU_CHECK_TESTS:+"$GPU_CHECK_TESTS"} >>"$results/tests.log" 2>&1 || rc=$?
        done
        grep -E '^test result:' "$results/tests.log" | tee -a "$results/summary"
        (exit $rc)
        ;;
    bench)
        "$work/splitray" bench bdpt lamps fixture cornell-box \
            --integrators lvc-bdpt,cis-lbdpt --width "$size" --height "$size" --time 1 --rounds 1 \
            --spp "$spp" --spp-rounds 2 --streams 1,3 --sort on,off \
            --json "$results/bench-bdpt.json" >"$results/bench-bdpt.log" 2>&1
        ;;
    mse)
        equal_time >"$results/mse.log" 2>&1
        ;;
    esac
    record "$part" $? $((SECONDS - start))
done
exit $status
