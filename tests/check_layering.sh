#!/bin/sh
# SPDX-License-Identifier: BSD-3-Clause
# check_layering.sh - the tiers of src/README.md, checked by the #includes
# of each file (`make check-layering`, run by `make test`):
#
#   src/core    the kernel: no file format, no printing, no upper tier
#   src/cuda    the GPU (make CUDA=1): the kernel's formulas on the device;
#               no file format, no upper tier
#   <cuda_runtime.h>  only in src/cuda/*.cu, the only code that calls CUDA
#   src/io      file formats: nothing of the stencil
#   src/model   case and set-up: no app or CLI
#   render/     pictures from the HDF5 output: not the kernel, not HDF5
#               itself (it reads through snapshot.h, src/io/h5_read.c)
#   library     nothing of src/cli
#   include/    the installed headers: no internal header (they are not
#               installed), only each other
#   <hdf5.h>    only in the io/h5 files, src/io/h5_*: the only code that
#               speaks HDF5 (the reader, the writer and what they share);
#               their headers (io/h5_*.h, which hold HDF5 types) likewise
#
# Prints each offending line and exits 1; prints one line and exits 0
# when every rule holds.  Run from the top of the repository.
cd "$(dirname "$0")/.." || exit 2
fail=0

# check WHAT PATTERN FILE...: no FILE may include a header matching PATTERN
check() {
	what=$1 pattern=$2
	shift 2
	hits=$(grep -nE "^[[:space:]]*#[[:space:]]*include[[:space:]]*[<\"]($pattern)[>\"]" \
	       "$@" 2>/dev/null)
	if [ -n "$hits" ]; then
		echo "check-layering: $what:"
		echo "$hits" | sed 's/^/    /'
		fail=1
	fi
}

core_headers="include/sandslide/grid.h include/sandslide/boundary.h
include/sandslide/closure.h include/sandslide/stepper.h include/sandslide/diagnostics.h"
upper="sandslide/(snapshot|dem|render|run|relax|bench|case|shape|progress)\.h"

# shellcheck disable=SC2086
check "the kernel (src/core) includes a file format, stdio or an upper tier" \
	"hdf5\.h|hdf5_hl\.h|png\.h|gdal.*\.h|cpl_.*\.h|ini\.h|stdio\.h|(cuda|io|model|app|cli)/.*|$upper" \
	src/core/* $core_headers
# shellcheck disable=SC2086
check "the GPU tier (src/cuda) includes a file format or an upper tier" \
	"hdf5\.h|hdf5_hl\.h|png\.h|gdal.*\.h|cpl_.*\.h|ini\.h|(io|model|app|cli)/.*|$upper" src/cuda/*
cuda=$(grep -lE '^[[:space:]]*#[[:space:]]*include[[:space:]]*<cuda' -r src render include tests \
       | grep -vE '^src/cuda/[a-z0-9_]+\.cu$')
if [ -n "$cuda" ]; then
	echo "check-layering: a CUDA header outside src/cuda/*.cu:"
	echo "$cuda" | sed 's/^/    /'
	fail=1
fi
check "I/O (src/io) includes the stencil or an upper tier" \
	"sandslide/stepper\.h|core/.*|cuda/.*|(model|app|cli)/.*" src/io/*
check "the model set-up (src/model) includes an upper tier" "(app|cli)/.*" src/model/*
check "the renderer (render/) includes the kernel, HDF5 or an upper tier" \
	"hdf5\.h|hdf5_hl\.h|sandslide/(stepper|closure)\.h|core/.*|(model|app|cli)/.*" render/*
check "the library includes the command line (src/cli)" "cli/.*" \
	src/base/* src/core/* src/model/* src/io/* src/app/* render/* include/sandslide/*
check "a public header (include/sandslide) includes an internal one, which is not installed" \
	"(base|core|cuda|io|model|app|cli|render)/.*" include/sandslide/*

hdf5=$(grep -lE '^[[:space:]]*#[[:space:]]*include[[:space:]]*(<hdf5|"io/h5_)' -r src render include \
       tests/*.c | grep -vE '^src/io/h5_[a-z0-9_]+\.[ch]$')
if [ -n "$hdf5" ]; then
	echo "check-layering: <hdf5.h> or an io/h5 header outside the io/h5 files (src/io/h5_*):"
	echo "$hdf5" | sed 's/^/    /'
	fail=1
fi

[ $fail -eq 0 ] && echo "  layering: core, io, model, render and cli include only what they may"
exit $fail
