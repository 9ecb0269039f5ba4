#!/bin/sh
# SPDX-License-Identifier: BSD-3-Clause
# check_ptx.sh NVCC FLAGS... - the GPU's kernels keep every product and sum
# of face_point.h rounded on its own (doc/gpu.md#the-same-bits).
#
# Compiles each src/cuda/*.cu to PTX (nvcc -ptx, the build's flags: `make
# CUDA=1 test-cuda` passes them) and, in every function but CUDA's own math
# library (__internal_*: pow's polynomial, which fuses by design and is one
# reason Herschel-Bulkley by pow() has bits of its own), fails on
#   - a fused multiply-add (fma.*.f64): a * b + c rounded once, not twice;
#   - a double multiply, add or subtract without a rounding mode: ptxas may
#     contract mul.f64 + add.f64 into an FMA, never mul.rn.f64 + add.rn.f64;
#   - a reciprocal, division or square root that is not IEEE (.rn; the
#     approximate forms are .approx).
# Then the same kernels compiled with -fmad=true must have FMAs, so that
# this check can see one.  The PTX is all a machine without a GPU has
# (cuobjdump of the SASS needs the GPU machine's toolkit: tools/gpu_check.sh).
set -u
nvcc=$1
shift
cd "$(dirname "$0")/../.." || exit 2
out=$(mktemp -d) || exit 2
trap 'rm -rf "$out"' EXIT
fail=0
# the function each PTX line is in, and the lines that break the rules
offending() {
	awk '/^(\.visible |\.weak )?\.(entry|func)/ {
	         f = $0; gsub(/\(\.param[^)]*\)/, "", f); sub(/\(.*/, "", f)
	         n = split(f, w, " "); f = w[n] }
	     f !~ /^__internal_/ && /^[[:space:]]*(fma\.[a-z.]*f64|(mul|add|sub)\.f64|(div|rcp|sqrt)\.approx[a-z.]*f64)/ {
	         print f ": " $0 }' "$1"
}
for cu in src/cuda/*.cu; do
	name=$(basename "$cu" .cu)
	"$nvcc" "$@" -ptx "$cu" -o "$out/$name.ptx" || { echo "check_ptx: nvcc -ptx $cu failed"; exit 1; }
	bad=$(offending "$out/$name.ptx")
	if [ -n "$bad" ]; then
		echo "check_ptx: $cu: operations that may round otherwise than the CPU's:"
		echo "$bad" | head -20 | sed 's/^/    /'
		fail=1
	fi
	ops=$(grep -cE '^[[:space:]]*(mul|add|sub)\.rn\.f64' "$out/$name.ptx")
	[ -n "$bad" ] || echo "check_ptx: $cu: $ops products and sums, each .rn; no FMA outside CUDA's math library"
	# the check sees an FMA where there is one
	args=""
	for a in "$@"; do
		case $a in -fmad=false) args="$args -fmad=true" ;; *) args="$args $a" ;; esac
	done
	# shellcheck disable=SC2086
	"$nvcc" $args -ptx "$cu" -o "$out/$name.fmad.ptx" || exit 1
	fused=$(offending "$out/$name.fmad.ptx" | grep -c 'fma\.')
	if [ "$fused" -eq 0 ] && [ "$ops" -gt 0 ]; then
		echo "check_ptx: $cu with -fmad=true has no FMA either: the check cannot see one"
		fail=1
	else
		echo "check_ptx: $cu with -fmad=true: $fused FMAs found (the check sees them)"
	fi
done
exit $fail
