#!/usr/bin/env bash
# Writes a scene TOML of COUNT copies of the Stanford bunny (69,451 triangles each) in a
# grid of rows facing the default camera, for the large-scene benchmarks of
# docs/PERFORMANCE.md: COUNT = 144 is 10,000,944 triangles, COUNT = 60 is 4,167,060.
# The bunny is not shipped with splitray; the scene refers to it by absolute path.
#
#   tools/bunny-grid.sh 144 /tmp/bunnies-10m.toml [path/to/bunny.obj]
#   splitray bench trace /tmp/bunnies-10m.toml --tracers pdacrt
set -euo pipefail
usage="usage: $0 COUNT OUT.toml [BUNNY.obj]"
count=${1:?$usage}
out=${2:?$usage}
here=$(cd "$(dirname "$0")" && pwd)
# Default: ../shared/meshes beside the checkout, else shared/meshes inside it.
bunny=${3:-$here/../../shared/meshes/bunny/bunny.obj}
[[ -n ${3:-} || -f $bunny ]] || bunny=$here/../shared/meshes/bunny/bunny.obj
[[ -f $bunny ]] || { echo "$0: no bunny.obj at $bunny" >&2; exit 1; }
bunny=$(cd "$(dirname "$bunny")" && pwd)/$(basename "$bunny")
[[ $count =~ ^[1-9][0-9]*$ ]] || { echo "$0: COUNT must be a positive integer, not '$count'" >&2; exit 1; }
columns=$(awk "BEGIN{c = int(sqrt($count)); if (c * c < $count) c++; print c}")
{
    echo "# $count Stanford bunnies ($((count * 69451)) triangles) in rows of $columns, written by tools/bunny-grid.sh."
    echo "name = \"bunnies-$count\""
    for ((k = 0; k < count; k++)); do
        echo
        echo "[[mesh]]"
        echo "path = \"$bunny\""
        echo "transform = { translate = [$(awk "BEGIN{print 0.2 * ($k % $columns)}"), $(awk "BEGIN{print 0.2 * int($k / $columns)}"), 0.0] }"
    done
} > "$out"
echo "$out: $count bunnies, $((count * 69451)) triangles"
