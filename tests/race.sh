#!/bin/sh
# SPDX-License-Identifier: BSD-3-Clause
# tests/race.sh BUILD - the data-race check that `make race` runs.
#
# BUILD holds sandslide and the C tests built with clang -fsanitize=thread
# against LLVM's libomp; the caller sets OMP_TOOL_LIBRARIES to Archer's
# libarcher.so (which tells ThreadSanitizer about OpenMP's barriers,
# reductions and tasks, so that it reports only real races), TSAN_OPTIONS
# and SANDSLIDE_TEST_SCALE.  Everything runs on 2 threads.
#
#   C tests     test_sweep: the fast sweep against the reference sweep with
#               walls, open cells and sides, periodic sides, two sources
#               switching, bedrock limits, tiles 1x3 .. 64x64, 1 and 2
#               threads; test_physics: the stepper end to end; test_render
#               (frames split by rows), test_dem, test_closure, test_watch
#               (a watch read and stopped from another thread)
#   CLI         a small case with a wall, an open pit, an open side, a source
#               and a bedrock, through both kernels, --tile 8x4; relax of a
#               cliff DEM; render of the series (frames between threads) and
#               oblique; bench (its own kernels)
#
# A ThreadSanitizer report makes the program exit 66 (TSAN_OPTIONS
# exitcode), so it counts as a failure here.  Ends with "N passed, M failed".
set -u
build=${1:?usage: tests/race.sh BUILD}
here=$(cd "$(dirname "$0")" && pwd)
bin=$(cd "$build" && pwd)/sandslide
tmp=$(mktemp -d "${TMPDIR:-/tmp}/sandslide-race.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
export OMP_NUM_THREADS=2
passed=0
failed=0

check() {
	what=$1
	shift
	start=$(date +%s)
	if "$@" >"$tmp/log" 2>&1; then
		passed=$((passed + 1))
		echo "ok   $what ($(($(date +%s) - start)) s)"
	else
		rc=$?
		failed=$((failed + 1))
		echo "FAIL $what (exit $rc)"
		# the reports, or the end of the output
		if grep -q 'ThreadSanitizer' "$tmp/log"; then
			sed -n '/WARNING: ThreadSanitizer/,/^SUMMARY/p' "$tmp/log" | head -200
		else
			tail -20 "$tmp/log"
		fi
	fi
}

for t in test_sweep test_physics test_render test_dem test_closure test_watch; do
	check "$t" "$build/tests/$t"
done

# 48 x 40 cells of 2.5 cm: a steep cone on a floor 5 cm thick over a flat
# bedrock at 2 cm, a wall block, an open pit, an open east side, a source
# on for the first fifth of the run
cd "$tmp" || exit 1
cat >case.ini <<'EOF'
[grid]
nx = 48
ny = 40
dx = 0.025
origin = 0 0

[model]
closure = bingham
repose_angle = 35
nu = 0.05

[time]
end = 1
output_every = 0.25

[boundary]
west = wall
east = open
south = wall
north = wall
open_level = 0

[initial]
type = cone
center = 0.4 0.5
radius = 0.35
angle = 55
height = 0.05
bedrock = bed.asc

[wall block]
rect = 0.70 0.30 0.85 0.55

[open pit]
disk = 0.25 0.20 0.06

[source pour]
rect = 0.10 0.70 0.30 0.90
rate = 0.05
start = 0
stop = 0.2
EOF
# An ESRI ASCII grid of $1 x $2 cells of $3 m on stdout: the value of cell
# (i, j), j counted from the north row, is the v that function $4 sets for i j.
raster() {
	printf 'ncols %s\nnrows %s\nxllcorner 0\nyllcorner 0\ncellsize %s\n' "$1" "$2" "$3"
	j=0
	while [ $j -lt "$2" ]; do
		i=0
		row=""
		while [ $i -lt "$1" ]; do
			$4 $i $j
			row="$row $v"
			i=$((i + 1))
		done
		echo "$row"
		j=$((j + 1))
	done
}
flat_bed() { v=0.02; }
raster 48 40 0.025 flat_bed >bed.asc

check "run, fast kernel, tiles 8x4" "$bin" run case.ini -o fast.h5 -q --tile 8x4
check "run, reference kernel" "$bin" run case.ini -o ref.h5 -q --reference-kernel
check "run, periodic sides" "$bin" run case.ini -o per.h5 -q --tile 8x4 \
	--set boundary.west=periodic --set boundary.east=periodic \
	--set boundary.south=periodic --set boundary.north=periodic
check "render series" "$bin" render fast.h5 -o frames --contour 0.02 --label
check "render oblique" "$bin" render fast.h5 -o oblique --frames -1 --style oblique
# a cliff: the western third 0.5 m higher
cliff() { if [ "$1" -lt 13 ]; then v=0.5; else v=0; fi; }
raster 40 24 0.05 cliff >cliff.asc
check "relax" "$bin" relax cliff.asc -o cliff-relaxed.asc --max-time 2
# until steady: forward Euler, then the approach to rest's super-steps
check "relax to rest, tiles 8x4" "$bin" relax cliff.asc -o cliff-rest.asc --tile 8x4
# materials: 30 and 40 degrees in bands of rows (doc/model.md#materials);
# hysteresis: the states updated between steps, a reduction of the threads
bands() { if [ $(($2 / 6 % 2)) -eq 0 ]; then v=30; else v=40; fi; }
raster 40 24 0.05 bands >angles.asc
check "relax, two materials, tiles 8x4" "$bin" relax cliff.asc -o cliff-angles.asc \
	--angle angles.asc --tile 8x4
check "relax, hysteresis, tiles 8x4" "$bin" relax cliff.asc -o cliff-hysteresis.asc \
	--angle 30 --static-angle 36 --tile 8x4
check "bench" "$bin" bench --nx 300 --ny 200 --tile 32x16 --closure bingham \
	--surface supercritical --repeats 1 --steps 2 --threads 2

echo "race: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
