#!/usr/bin/env bash
# Packs what checking splitray on another machine's GPU needs, for a machine with neither
# a Rust toolchain nor a Vulkan loader (a GPU node of a render farm, a cloud instance):
#
# - the release binary, for the benchmarks;
# - the test binaries (the library's unit tests and tests/suite, `ci` profile) and the
#   binary their command-line tests run, built where `make test` builds them;
# - Debian 12's Vulkan loader and validation layer, and the vendor-neutral GL dispatch
#   libraries (glvnd) through which NVIDIA's Vulkan driver is loaded.
#
# Binaries are stripped and gzipped: the bundle is about 30 MB. It goes with the checkout
# it was built from (the tests read scenes and references from it); on the GPU machine,
# `tools/gpu-check.sh` runs it in a copy of that checkout:
#
#   tools/gpu-bundle.sh                 # here: writes .gpu-bundle/ (git-ignored)
#   tools/gpu-check.sh gpu-results/     # there: device, tests with validation, benchmarks
#
# Needs Debian 12's apt (for the packages) and what `make build` installs.
set -euo pipefail
cd "$(dirname "$0")/.."
bundle=${1:-.gpu-bundle}
packages=(libvulkan1 vulkan-validationlayers libglvnd0 libgl1 libglx0 libegl1 libopengl0 libgles2)

cargo build --release --locked
# The `ci` binary the command-line tests run (CARGO_BIN_EXE_splitray) is built with them;
# cargo names each test executable as "Executable <source> (<path>)".
built=$(cargo test --profile ci --locked --no-run --lib --test suite 2>&1) ||
    { echo "$built" >&2; exit 1; }
tests=$(sed -n 's/^ *Executable .*(\(.*\))$/\1/p' <<<"$built")

rm -rf "$bundle"
mkdir -p "$bundle/debs"
pack() { # pack SOURCE NAME: a stripped, gzipped copy of binary SOURCE as NAME.gz
    strip -o "$bundle/$2" "$1"
    gzip -9 "$bundle/$2"
}
pack target/release/splitray splitray
pack target/ci/splitray splitray-ci
names=()
for path in $tests; do
    name=test-$(basename "$path" | sed 's/-[0-9a-f]*$//') # deps/suite-<hash>: test-suite
    pack "$path" "$name"
    names+=("$name")
done
[[ ${#names[@]} -eq 2 ]] || { echo "$0: expected 2 test binaries, found: ${names[*]}" >&2; exit 1; }

(cd "$bundle/debs" && apt-get -q -o APT::Sandbox::User=root download "${packages[@]}")

# Where the tests were built: their paths to the checkout (scenes, references) and to
# the `ci` binary are compiled in, and gpu-check.sh makes them point to its copy.
cat >"$bundle/manifest" <<EOF
BUILD_ROOT=$PWD
COMMIT=$(git rev-parse HEAD)$(git diff --quiet HEAD -- src glsl tests build.rs Cargo.toml Cargo.lock || echo -dirty)
BUILT=$(date -u +%Y-%m-%dT%H:%M:%SZ)
TESTS="${names[*]}"
EOF
du -sh "$bundle"
echo "$bundle: $(grep COMMIT "$bundle/manifest"); run tools/gpu-check.sh on the GPU machine"
