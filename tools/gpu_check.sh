#!/bin/sh
# SPDX-License-Identifier: BSD-3-Clause
# gpu_check.sh - the GPU backend's checks and figures on a GPU machine, in
# one run of at most 8 minutes (doc/gpu.md#checking-on-a-gpu).
#
#   tools/gpu_check.sh --pack      here, on a CPU machine with the build's
#                                  packages: make CUDA=1 GDAL=0 into
#                                  build-gpu/ (the program and the GPU
#                                  test) and the shared libraries they load into
#                                  build-gpu/lib/ (the GPU machine has
#                                  nvcc and a driver, not HDF5 or libpng);
#                                  prints its size (the device tool carries
#                                  at most 64 MiB)
#   tools/gpu_check.sh [OUT]       there, from the checkout's root with
#                                  build-gpu/ carried: the checks, then the
#                                  figures, one table; everything also into
#                                  OUT/gpu_check.txt (OUT: $OUT, else .)
#
# The checks: nvidia-smi; the PTX check (tests/gpu/check_ptx.sh with the
# machine's nvcc) and the SASS's double FMAs (cuobjdump, only there);
# build-gpu/tests/gpu/test_cuda (the device's loop against the CPU's
# generic path, bit for bit, every closure and kind of side); tests/gpu
# and tests/cli/test_device.py (pytest).
# The figures: bench --device cuda at 4096^2, 8192^2 and 16384^2 (Coulomb,
# supercritical and patch), the device-to-device copy's bandwidth, and the
# fraction of the 26 B/cell-update roofline; the room, relax and run are not
# on the GPU yet (doc/gpu.md#what-runs-on-the-gpu) and say so.
set -u
cd "$(dirname "$0")/.." || exit 2
B=build-gpu

if [ "${1:-}" = "--pack" ]; then
	make -j"$(nproc)" CUDA=1 GDAL=0 BUILD=$B all $B/tests/gpu/test_cuda || exit 1
	mkdir -p $B/lib
	# every shared library the programs load, but the C library's own and
	# the driver's (libcuda comes from the GPU machine)
	for bin in $B/sandslide $B/tests/gpu/test_cuda $B/libsandslide.so; do
		ldd "$bin" | awk '$3 ~ /^\// { print $3 }'
	done | sort -u |
	grep -vE '/(libc|libm|libdl|librt|libpthread|ld-linux[^/]*|libcuda|libstdc\+\+|libgcc_s)\.so' |
	while read -r lib; do cp -L "$lib" $B/lib/; done
	# what the checks there do not need (they run no make)
	rm -rf $B/obj $B/fuzz $B/gen $B/hdrcheck $B/libsandslide.a
	du -sh $B
	echo "gpu_check: carry $B (with the device tool: carry=[\"$B\"]), then run tools/gpu_check.sh"
	exit 0
fi

OUTDIR=${1:-${OUT:-.}}
mkdir -p "$OUTDIR"
LOG=$OUTDIR/gpu_check.txt
export LD_LIBRARY_PATH="$PWD/$B/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-16}
: > "$LOG"
say() { echo "$@" | tee -a "$LOG"; }
# step TITLE COMMAND...: its output to the screen and the log, its status
step() {
	say "== $1"
	shift
	"$@" > "$OUTDIR/step.txt" 2>&1
	rc=$?
	cat "$OUTDIR/step.txt"
	cat "$OUTDIR/step.txt" >> "$LOG"
	rm -f "$OUTDIR/step.txt"
	return $rc
}
START=$(date +%s)
fail=0
[ -x $B/sandslide ] || { say "gpu_check: no $B/sandslide: run tools/gpu_check.sh --pack first and carry $B"; exit 2; }

step "nvidia-smi" nvidia-smi --query-gpu=name,memory.total,driver_version,clocks.max.sm --format=csv
step "version" $B/sandslide --version

# ---- checks ---------------------------------------------------------------
NVCC=${NVCC:-$(command -v nvcc || echo /usr/local/cuda/bin/nvcc)}
step "PTX: no fused multiply-add" sh tests/gpu/check_ptx.sh "$NVCC" -std=c++17 -O3 \
	-fmad=false -prec-div=true -prec-sqrt=true -ftz=false -arch=compute_90 -Iinclude -Isrc \
	-DSS_HAVE_CUDA || fail=1
if command -v cuobjdump > /dev/null; then
	# the machine code the build put in the program: DFMA outside CUDA's
	# math library (pow) would be a fused a * b + c
	cuobjdump --dump-sass $B/sandslide > "$OUTDIR/sass.txt" 2>&1
	dfma=$(awk '/Function :/ { f = $3 } /DFMA/ && f !~ /internal/ { n++ } END { print n + 0 }' "$OUTDIR/sass.txt")
	say "== SASS: $(grep -c 'Function :' "$OUTDIR/sass.txt") functions, $dfma DFMA outside CUDA's math library"
	[ "$dfma" -eq 0 ] || fail=1
fi
step "test_cuda (the device's loop against the generic path)" $B/tests/gpu/test_cuda || fail=1
if python3 -c "import pytest" 2> /dev/null; then
	SANDSLIDE=$PWD/$B/sandslide step "tests/gpu, tests/cli/test_device.py" \
		python3 -m pytest -q -rs -p no:cacheprovider tests/gpu tests/cli/test_device.py || fail=1
fi

# ---- figures --------------------------------------------------------------
if ! $B/sandslide --version | grep -q '^  cuda:0: '; then
	say "gpu_check: no GPU here: no figures"
	exit 1
fi
say "== bench on the GPU (Coulomb; cell-updates/s, median of 5; roofline 26 B/cell-update)"
for n in 4096 8192 16384; do
	step "bench ${n}^2" timeout 150 $B/sandslide bench --device cuda --nx $n --ny $n \
		--closure coulomb --surface supercritical --repeats 5 || fail=1
	[ $(( $(date +%s) - START )) -lt 360 ] || { say "gpu_check: 6 minutes gone: the rest left out"; break; }
done
step "bench 8192^2, every closure" timeout 120 $B/sandslide bench --device cuda --nx 8192 \
	--ny 8192 --closure all --surface all --repeats 3 || fail=1
step "the same without CUDA graphs (launch cost)" env SANDSLIDE_CUDA_GRAPH=0 timeout 60 \
	$B/sandslide bench --device cuda --nx 1024 --ny 1024 --closure coulomb \
	--surface supercritical --repeats 5
step "the CPU (16 threads, AVX-512 if there) beside it" timeout 60 $B/sandslide bench \
	--nx 4096 --ny 4096 --closure coulomb --surface supercritical --threads 16 --repeats 3
say "== not on the GPU yet: run (the door 480 x 320 to t = 1000 s), relax (terrain.asc, 2048^2 and 8192^2 fractals) (doc/gpu.md#what-runs-on-the-gpu)"
say "gpu_check: $(( $(date +%s) - START )) s, $( [ $fail -eq 0 ] && echo 'every check passed' || echo 'SOME CHECK FAILED')"
exit $fail
