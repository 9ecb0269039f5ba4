# SPDX-License-Identifier: BSD-3-Clause
# sandslide - plain GNU Makefile.
#
#   make            build build/sandslide, build/libsandslide.a and .so, and
#                   the man page build/sandslide.1 (man -l build/sandslide.1)
#   make lib        only the shared library build/libsandslide.so.0 (what
#                   the Python module loads; pip's build runs it, setup.py)
#   make deps       install the Debian packages building and running need
#   make deps-test  add those the test suite needs (pytest, GDAL's tools,
#                   xarray, CDO, ParaView, Chromium and selenium for the
#                   HTML viewer, clang for the race check)
#   make deps-bench add the real DEMs tools/real_dems.py writes for the
#                   benchmarks (BENCH_ALL=1: those of --all too); not tests
#   make deps-slurm add Slurm and munge for `make MPI=1 test-slurm`
#   make test       build and run every test (C programs, then CLI tests)
#   make test-hooks the hooked sandslide binaries the CLI tests run
#                   (build/tests/sandslide-nan, -pause; `make test` builds them):
#                   with `make`, what one CLI test file run alone needs
#   make install    bin, lib (.so and .a), headers, sandslide.pc, the man
#                   page, the example cases and the Python module under
#                   PREFIX (/usr/local), staged in DESTDIR; make uninstall
#   make demo       build, then run the door case into out/demo.h5 (again on
#                   every call: its own file, so that `sandslide run
#                   cases/door.ini`, the README's next step, finds out/door.h5 free)
#   make OPENMP=0   build without OpenMP (pragmas must still compile)
#   make NATIVE=1   build for this machine's processor (-march=native); the
#                   default build runs on any x86-64 (AVX-512 chosen at run time)
#   make SANITIZE=1 AddressSanitizer + UndefinedBehaviorSanitizer, in build-san/
#                   (`make SANITIZE=1 test` runs every test with them)
#   make race       data-race check of the OpenMP code: ThreadSanitizer + Archer
#   make MPI=1      build-mpi/sandslide with Open MPI and parallel HDF5
#                   (`make deps MPI=1` installs them; `make MPI=1 test-mpi`
#                   runs the distributed tests, tests/cli/test_mpi.py;
#                   `make MPI=1 test-slurm` runs doc/cluster.md's Slurm job
#                   on a one-node Slurm started here, as root)
#   make CUDA=1     build-cuda/sandslide with the GPU backend (nvcc from
#                   CUDA_HOME, /usr/local/cuda; CUDA_ARCHS=90, the H100's
#                   and H200's sm_90, as a list: CUDA_ARCHS="80 90");
#                   `make CUDA=1 test-cuda` checks the kernels' PTX and
#                   runs tests/gpu/, whose GPU tests skip without a GPU
#                   (doc/gpu.md)
#   make check-layering  the tiers of src/README.md, by their #includes
#   make FONT=FILE  build with another default font for the text of pictures
#                   (DejaVu Sans of fonts-dejavu-core otherwise; SANDSLIDE_FONT
#                   chooses one at run time)
#   make V=1        show the full commands
#
# User CFLAGS/LDFLAGS are appended last, never overwritten.

# A sanitized or MPI build has its own folder: build/ is left as it is.
ifeq ($(SANITIZE),1)
  BUILD    ?= build-san
endif
ifeq ($(MPI),1)
  BUILD    ?= build-mpi
endif
ifeq ($(CUDA),1)
  BUILD    ?= build-cuda
endif
BUILD      ?= build
PKG_CONFIG ?= pkg-config
PYTHON     ?= /usr/bin/python3
MPI        ?= 0
CUDA       ?= 0
ifeq ($(MPI),1)
  # Open MPI, Debian's default MPI, named explicitly: mpicc is an
  # alternative that another MPI may have taken
  CC       := mpicc.openmpi
endif
CC         ?= cc
OPENMP     ?= 1
SANITIZE   ?= 0
VERSION    := 0.1.0
# The shared library's ABI version: the soname is libsandslide.so.$(SOVERSION).
# 0 while the public headers may still change from one release to the next.
SOVERSION  := 0

.DELETE_ON_ERROR:
.DEFAULT_GOAL := all

# Debian package that provides each pkg-config module we need.  HDF5 is
# named by flavour: installing libhdf5-openmpi-dev turns plain `hdf5` into
# the parallel one (Debian's alternatives, priority 35 over 20), which a
# serial build must not pick up.
DEB_hdf5-serial  := libhdf5-dev
DEB_hdf5-openmpi := libhdf5-openmpi-dev
DEB_libpng := libpng-dev
# zlib (libpng's own compressor) deflates the heights of render --html
DEB_zlib   := zlib1g-dev
DEB_inih   := libinih-dev
# NLopt: the bounded derivative-free search of `sandslide fit` (BOBYQA)
DEB_nlopt  := libnlopt-dev
# FreeType: the text of pictures (render/text.c: the time label, the colour
# bar, fit --plot's figures), in the font FONT below
DEB_freetype2 := libfreetype-dev
ifeq ($(MPI),1)
  PC_HDF5  := hdf5-openmpi
else
  PC_HDF5  := hdf5-serial
endif
PC_MODULES := $(PC_HDF5) libpng zlib inih nlopt freetype2
DEB_BUILD  := pkg-config $(foreach m,$(PC_MODULES),$(DEB_$(m)))
ifeq ($(MPI),1)
  DEB_BUILD += openmpi-bin libopenmpi-dev
endif
# Run time: ffmpeg for render --video, numpy for the Python module, and the
# font of the pictures' text: DejaVu Sans, at the path Debian's
# fonts-dejavu-core installs it (FONT=FILE builds with another default; at
# run time SANDSLIDE_FONT=FILE chooses one; without the file, drawing text
# fails with one line naming both).
DEB_RUN    := ffmpeg python3-numpy fonts-dejavu-core
FONT       ?= /usr/share/fonts/truetype/dejavu/DejaVuSans.ttf
FONT_FLAG  := -DSS_FONT_FILE='"$(FONT)"'
# The test suite's tools: the CLI tests (pytest, h5py), and the programs
# that check the outputs open as they are (ncdump, gdalinfo and GDAL's
# Python bindings, xarray with netCDF4, CDO, ParaView's pvbatch).  Debian's
# python3-vtk9 conflicts with python3-paraview, so VTK's readers are
# tested inside pvbatch.
DEB_TEST   := python3-h5py python3-pytest netcdf-bin gdal-bin python3-gdal \
              python3-xarray python3-netcdf4 cdo paraview python3-paraview man-db groff-base
# render --html's page is tested in headless Chromium through selenium
# (tests/cli/test_html.py), its screenshot read with PIL
DEB_TEST   += chromium chromium-driver python3-selenium python3-pil
# the coupled BMI example's --png (python/examples/wind_deposition.py; its
# test draws the picture when matplotlib is there)
DEB_TEST   += python3-matplotlib
# `pip install .` into a fresh virtual environment, offline, with Debian's
# build tools (tests/python/test_pip.py; pyproject.toml, setup.py)
DEB_TEST   += python3-pip python3-venv python3-setuptools python3-wheel
# The benchmarks' real DEMs (tools/real_dems.py, read by
# tools/time_to_solution.py --workloads relax): the Debian packages that
# ship them, the reader of R's data files, h5py for the outputs.  About
# 100 MB installed (R's core, OpenFOAM's tutorials); BENCH_ALL=1 adds the
# GeoTIFFs of --all (R's sf stack: about 100 MB more).  Never on the
# test path.
DEB_BENCH  := python3-h5py python3-rdata r-base-core r-cran-spatstat.data \
              openfoam-examples python-matplotlib-data
ifeq ($(BENCH_ALL),1)
  DEB_BENCH += python3-gdal r-cran-satellite r-cran-stars r-cran-terra
endif
# A real Slurm on this one machine (tests/slurm/run.sh, make MPI=1
# test-slurm): the controller, the node daemon, sbatch/srun/sinfo, and
# munge, which signs their messages.  Not slurm-wlm, which adds slurmdbd
# and the plugins for what a single test node never uses.  srun
# --mpi=pmix's plugin dlopens pmix2/lib/libpmix.so, the unversioned name
# that only libpmix-dev ships (libopenmpi-dev pulls it in too).
DEB_SLURM  := slurmctld slurmd slurm-client munge libpmix-dev

# Goals that need no library: do not probe pkg-config for them.
NO_PROBE_GOALS := deps deps-test deps-bench deps-slurm clean help uninstall
ifeq ($(filter-out $(NO_PROBE_GOALS),$(or $(MAKECMDGOALS),all)),)
else
  ifeq ($(shell command -v $(PKG_CONFIG) 2>/dev/null),)
    $(error pkg-config not found: install Debian package 'pkg-config' (or run 'make deps'))
  endif
  $(foreach m,$(PC_MODULES),$(if $(shell $(PKG_CONFIG) --exists $(m) && echo y),,\
    $(error library '$(m)' not found by pkg-config: install Debian package '$(DEB_$(m))' (or run 'make deps'))))
  $(if $(wildcard $(FONT)),,$(warning font '$(FONT)' not found: pictures with text (--label, --colorbar, fit --plot) will fail until Debian package 'fonts-dejavu-core' is installed (or run 'make deps'), or SANDSLIDE_FONT names a font))
  DEP_CFLAGS := $(shell $(PKG_CONFIG) --cflags $(PC_MODULES))
  # The HDF5 high-level library (H5DS dimension scales) has no .pc file of
  # its own on Debian; it sits beside libhdf5.
  DEP_LIBS   := $(shell $(PKG_CONFIG) --libs $(PC_MODULES)) -lhdf5_hl
endif

# Optional GDAL: GeoTIFF and other GDAL rasters in src/io/dem_gdal.c.  Used
# when pkg-config finds it (GDAL=0 builds without); otherwise .tif input
# and output fail with "unavailable in this build".  `make deps` installs
# it: DEMs come as GeoTIFFs (about 100 packages, 54 MB: 34 s on the dev VM).
# The MPI build has it too: GDAL links the serial HDF5 and sandslide the
# parallel one, and both load in one process because Debian versions their
# symbols per flavour (GDAL's H5Fopen is H5Fopen@HDF5_SERIAL_1.8.7, ours
# H5Fopen@HDF5_MPI_1.8.7; doc/cluster.md#build-and-run).
GDAL ?= 1
DEB_BUILD += libgdal-dev
ifeq ($(GDAL),1)
  ifneq ($(filter-out $(NO_PROBE_GOALS),$(or $(MAKECMDGOALS),all)),)
    ifeq ($(shell $(PKG_CONFIG) --exists gdal 2>/dev/null && echo y),y)
      # -isystem: GDAL's headers are not -Wpedantic clean (ogr_core.h enums)
      DEP_CFLAGS += $(patsubst -I%,-isystem %,$(shell $(PKG_CONFIG) --cflags gdal)) -DSS_HAVE_GDAL
      DEP_LIBS   += $(shell $(PKG_CONFIG) --libs gdal)
    endif
  endif
endif

WARN     := -Wall -Wextra -Wpedantic -Wstrict-prototypes -Wshadow
# The instruction set.  By default the baseline of the compiler's target
# (x86-64: SSE2), so that a build, `make install` and the library Python
# loads run on any x86-64 machine of the distribution.  The kernel's hot
# loops (KERNEL_SRC) are compiled twice more, for AVX2 and for AVX-512, and
# the best copy the processor runs is chosen at run time
# (include/sandslide/cpu.h; SANDSLIDE_CPU=generic|avx2|avx512 forces one).
# NATIVE=1: everything for this machine (-march=native), a program that may
# die of SIGILL on another; the copies and the choice stay.
# The path decides the bits, not -march: the AVX-512 copy of the face flux
# has its own reciprocal square root (face.h); otherwise each operation is
# rounded once whichever instructions do it, with no a * b + c contracted
# into an FMA (-ffp-contract=off: gcc's ISO C mode implies it, clang's
# does not).
NATIVE   ?= 0
ifeq ($(NATIVE),1)
  ARCHFLAG := -march=native
endif
ifneq ($(filter x86_64-%,$(shell $(CC) -dumpmachine 2>/dev/null)),)
  KERNEL_PATHS := avx2 avx512
  PATHDEF      := -DSS_KERNEL_PATHS
endif
KERNEL_SRC        := src/core/face.c src/core/sweep_fast.c
# each copy's instruction set: what ss_cpu_path_supported checks (cpu.c)
PATHFLAGS_avx2    := -DSS_PATH=SS_PATH_AVX2 -mavx2
PATHFLAGS_avx512  := -DSS_PATH=SS_PATH_AVX512 -mavx2 -mavx512f -mavx512cd -mavx512vl \
                     -mavx512bw -mavx512dq
# -fno-math-errno lets sqrt() vectorise (errno is never read); it changes
# no result.  Never -ffast-math: it breaks determinism and the NaN checks.
BASE     := -std=c11 -D_XOPEN_SOURCE=700 -O3 $(ARCHFLAG) -ffp-contract=off -fno-math-errno -g
ifeq ($(OPENMP),1)
  OMPFLAG := -fopenmp
else
  OMPFLAG := -Wno-unknown-pragmas
endif
ifeq ($(SANITIZE),1)
  # float-cast-overflow (not part of `undefined`): a double converted to an
  # integer it does not fit, NaN included, e.g. a coordinate to a cell index
  SANFLAG := -fsanitize=address,undefined,float-cast-overflow -fno-omit-frame-pointer \
             -fno-sanitize-recover=undefined,float-cast-overflow
  # Run-time options for every program `make SANITIZE=1 test` starts (the CLI
  # tests' sandslide too): any report (a leak too) exits 86, failing the test
  # that caused it whatever exit status it expects.
  # SANDSLIDE_TEST_SCALE shrinks the longest test cases (each test file says
  # how at its top); every check still runs.
  export ASAN_OPTIONS ?= detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1:exitcode=86
  export UBSAN_OPTIONS ?= print_stacktrace=1:halt_on_error=1:exitcode=86
  export SANDSLIDE_TEST_SCALE ?= 0.5
endif
ifeq ($(MPI),1)
  MPIFLAG := -DSS_HAVE_MPI
endif
# The GPU backend (doc/gpu.md): src/cuda/*.cu compiled by nvcc for each
# architecture in CUDA_ARCHS (machine code, and PTX for newer GPUs to
# compile at load), the CUDA runtime linked statically (no path to find
# at run time; the driver, libcuda, is loaded by it when there is one).
# -fmad=false: no a * b + c fused into an FMA (the CPU's -ffp-contract=off);
# IEEE division and square root (nvcc's defaults, named): the device's bits
# are the CPU's generic path's (face_point.h, tests/gpu/check_ptx.sh).
CUDA_HOME  ?= /usr/local/cuda
NVCC       ?= $(CUDA_HOME)/bin/nvcc
CUDA_ARCHS ?= 90
NVCC_FP    := -fmad=false -prec-div=true -prec-sqrt=true -ftz=false
ifeq ($(CUDA),1)
  ifeq ($(wildcard $(NVCC)),)
    ifneq ($(filter-out $(NO_PROBE_GOALS),$(or $(MAKECMDGOALS),all)),)
      $(error make CUDA=1: no nvcc at $(NVCC): set CUDA_HOME to the CUDA toolkit (Debian has none; NVIDIA's, 12 or later))
    endif
  endif
  CUDAFLAG  := -DSS_HAVE_CUDA
  CU_SRC    := $(wildcard src/cuda/*.cu)
  NVCC_FLAGS := -std=c++17 -O3 $(NVCC_FP) \
                $(foreach a,$(CUDA_ARCHS),-gencode arch=compute_$(a),code=[sm_$(a),compute_$(a)]) \
                -Xcompiler -fPIC,-Wall,-Wextra -Iinclude -Isrc $(CUDAFLAG) -MMD -MP
  CUDA_LIBS := -L$(CUDA_HOME)/lib64 -L$(CUDA_HOME)/lib -lcudart_static -lstdc++ -ldl -lrt -lpthread
endif
# Sources made by the build (the viewer's script as a C array): GEN, on
# the include path of every build of the library.  The top folder is on it
# too, for the renderer's headers that other tiers include as
# "render/plot.h" (private to the library: include/sandslide/ is the
# installed interface).
GEN      := $(BUILD)/gen
# -fPIC: the same objects make the static and the shared library (on
# x86-64 the kernel's loops make no calls through the PLT or GOT, so the
# sweep runs as fast: doc/performance.md#how-the-figures-were-measured).
ALL_CFLAGS  := $(BASE) -fPIC $(WARN) $(OMPFLAG) $(SANFLAG) $(MPIFLAG) $(CUDAFLAG) $(PATHDEF) -Iinclude -Isrc \
               -I. -I$(GEN) \
               -DSS_VERSION='"$(VERSION)"' $(FONT_FLAG) \
               $(DEP_CFLAGS) -MMD -MP $(CFLAGS)
ALL_LDFLAGS := $(OMPFLAG) $(SANFLAG) $(LDFLAGS)
LIBS        := $(DEP_LIBS) $(CUDA_LIBS) -lm

ifeq ($(V),1)
  Q :=
else
  Q := @
endif

# The library in tiers (src/README.md): base, core, io, model, app; the
# command line in src/cli/ is the program around it.
LIB_SRC  := $(filter-out src/cli/%,$(wildcard src/*/*.c))
CLI_SRC  := $(wildcard src/cli/*.c)
# The renderer (render/, doc/rendering.md) is part of the library.
RENDER_SRC := $(wildcard render/*.c)
LIB_OBJ  := $(LIB_SRC:src/%.c=$(BUILD)/obj/%.o) $(RENDER_SRC:render/%.c=$(BUILD)/obj/render/%.o)
# the kernel's copies per instruction-set path: FILE-avx2.o, FILE-avx512.o
KERNEL_OBJ := $(foreach p,$(KERNEL_PATHS),$(KERNEL_SRC:src/%.c=$(BUILD)/obj/%-$(p).o))
LIB_OBJ  += $(KERNEL_OBJ) $(CU_SRC:src/%.cu=$(BUILD)/obj/%.cu.o)
MAIN_OBJ := $(CLI_SRC:src/%.c=$(BUILD)/obj/%.o)
TEST_SRC := $(wildcard tests/test_*.c)
TEST_BIN := $(TEST_SRC:tests/%.c=$(BUILD)/tests/%)
# The public headers, installed: include/sandslide/ holds only them (the
# internal ones sit beside their sources, src/README.md).
HEADERS  := $(wildcard include/sandslide/*.h)

.PHONY: all lib deps deps-test deps-bench deps-slurm test check demo clean headers-check check-layering help \
        install uninstall
SONAME   := libsandslide.so.$(SOVERSION)
SHLIB    := libsandslide.so.$(VERSION)
all: $(BUILD)/sandslide $(BUILD)/libsandslide.a $(BUILD)/libsandslide.so $(BUILD)/sandslide.1
lib: $(BUILD)/libsandslide.so

# A flags stamp: objects rebuild when the flags change (git's GIT-CFLAGS).
STAMP := $(ALL_CFLAGS) $(PATHFLAGS_avx2) $(PATHFLAGS_avx512) $(ALL_LDFLAGS) $(LIBS) $(NVCC_FLAGS)
$(BUILD)/.flags: FORCE
	@mkdir -p $(@D)
	@echo '$(STAMP)' | cmp -s - $@ || echo '$(STAMP)' > $@
FORCE:

$(BUILD)/obj/%.o: src/%.c $(BUILD)/.flags
	@mkdir -p $(@D)
	@$(if $(Q),echo '  CC      $<')
	$(Q)$(CC) $(ALL_CFLAGS) -c $< -o $@

$(BUILD)/obj/%-avx2.o: src/%.c $(BUILD)/.flags
	@mkdir -p $(@D)
	@$(if $(Q),echo '  CC      $< (avx2)')
	$(Q)$(CC) $(ALL_CFLAGS) $(PATHFLAGS_avx2) -c $< -o $@

$(BUILD)/obj/%-avx512.o: src/%.c $(BUILD)/.flags
	@mkdir -p $(@D)
	@$(if $(Q),echo '  CC      $< (avx512)')
	$(Q)$(CC) $(ALL_CFLAGS) $(PATHFLAGS_avx512) -c $< -o $@

$(BUILD)/obj/%.cu.o: src/%.cu $(BUILD)/.flags
	@mkdir -p $(@D)
	@$(if $(Q),echo '  NVCC    $<')
	$(Q)$(NVCC) $(NVCC_FLAGS) -c $< -o $@

$(BUILD)/obj/render/%.o: render/%.c $(BUILD)/.flags
	@mkdir -p $(@D)
	@$(if $(Q),echo '  CC      $<')
	$(Q)$(CC) $(ALL_CFLAGS) -c $< -o $@

# The HTML viewer's script, render/viewer.js, as a C array of its bytes
# (ss_render_viewer_js) that render/html.c includes: the page holds the
# file's bytes exactly, less its header comment (the // lines up to the
# first empty line, and that line: what the file says of itself).  awk,
# od and sed only (POSIX; xxd may be missing, no Python at build time).
# Every build that compiles html.c (the library's, the fuzz builds') has
# the header as a prerequisite: its first compile has no .d file yet.
VIEWER_JS := $(GEN)/render/viewer_js.h
$(VIEWER_JS): render/viewer.js
	@mkdir -p $(@D)
	@$(if $(Q),echo '  GEN     $@')
	$(Q)awk 'NR == 1 && /^\/\// { head = 1 } head && /^\/\// { next } \
	  head && /^$$/ { head = 0; next } { head = 0; print }' $< > $@.js
	$(Q)od -An -v -tx1 $@.js > $@.od
	$(Q){ echo '/* render/viewer.js as bytes, less its header comment: made by the'; \
	  echo ' * Makefile (awk, od, sed); edit render/viewer.js instead */'; \
	  echo 'static const unsigned char ss_render_viewer_js[] = {'; \
	  sed -e 's/ *\([0-9a-fA-F][0-9a-fA-F]\)/0x\1,/g' $@.od; \
	  echo '};'; } > $@.tmp
	$(Q)rm -f $@.js $@.od && mv $@.tmp $@
$(BUILD)/obj/render/html.o: $(VIEWER_JS)

$(BUILD)/libsandslide.a: $(LIB_OBJ)
	@$(if $(Q),echo '  AR      $@')
	$(Q)rm -f $@ && ar rcs $@ $^

# The shared library (for C programs through pkg-config, and the Python
# module), with its soname and the two links a build tree needs:
# libsandslide.so for -lsandslide, libsandslide.so.0 for the loader.  Every
# library it uses is linked in (--no-undefined; not under the sanitizers,
# whose run-time symbols the program provides).
ifneq ($(SANITIZE),1)
  SHLIB_CHECK := -Wl,--no-undefined
endif
$(BUILD)/$(SHLIB): $(LIB_OBJ)
	@$(if $(Q),echo '  LINK    $@')
	$(Q)$(CC) -shared -Wl,-soname,$(SONAME) $(SHLIB_CHECK) $(ALL_LDFLAGS) $^ $(LIBS) -o $@
$(BUILD)/libsandslide.so: $(BUILD)/$(SHLIB)
	$(Q)ln -sf $(SHLIB) $(BUILD)/$(SONAME) && ln -sf $(SONAME) $@

$(BUILD)/sandslide: $(MAIN_OBJ) $(BUILD)/libsandslide.a
	@$(if $(Q),echo '  LINK    $@')
	$(Q)$(CC) $(ALL_LDFLAGS) $^ $(LIBS) -o $@

$(BUILD)/tests/%: tests/%.c tests/check.h $(BUILD)/libsandslide.a $(BUILD)/.flags
	@mkdir -p $(@D)
	@$(if $(Q),echo '  CC      $<')
	$(Q)$(CC) $(ALL_CFLAGS) -Itests $< $(BUILD)/libsandslide.a $(ALL_LDFLAGS) $(LIBS) -o $@

# Every header compiles on its own: the public ones (HEADERS, installed)
# and the kernel's internal ones beside their sources (src/core/*.h,
# included as "core/sweep.h").
headers-check: $(BUILD)/.flags
	@mkdir -p $(BUILD)/hdrcheck
	$(Q)for h in $(HEADERS) $(wildcard src/core/*.h); do \
	  printf '#include "%s"\n' "$${h#*/}" > $(BUILD)/hdrcheck/t.c && \
	  $(CC) $(filter-out -MMD -MP,$(ALL_CFLAGS)) -fsyntax-only $(BUILD)/hdrcheck/t.c || exit 1; \
	done; echo "  headers compile on their own"

# ---- fuzzing (tests/fuzz/) --------------------------------------------------
# One harness per input reader: case (ss_case_parse), mask (PNG masks of
# shapes), asc and png (ss_dem_read), h5 (the HDF5 reader, snapshot.h).
#   make fuzz         libFuzzer binaries $(BUILD)/fuzz/fuzz_NAME, built with
#                     clang (FUZZ_CC), the library compiled again with the same
#                     sanitizers; tests/fuzz/README.md says how to run them
#   make fuzz-replay  the same harnesses with $(CC), ASan and UBSan and a plain
#                     main() (tests/fuzz/replay.c), run over
#                     tests/fuzz/corpus/NAME/ and tests/fuzz/regressions/NAME/:
#                     no clang needed; `make test` runs it too
FUZZ_NAMES   := case mask asc png h5
FUZZ_CC      ?= clang
FUZZ_BUILD   := $(BUILD)/fuzz
FUZZ_SAN     := -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer
FUZZ_CFLAGS  := -std=c11 -D_XOPEN_SOURCE=700 -O1 -g $(WARN) -Wno-unknown-pragmas -Iinclude -Isrc \
                -I. -I$(GEN) -Itests/fuzz -DSS_VERSION='"$(VERSION)"' $(FONT_FLAG) $(DEP_CFLAGS) \
                $(FUZZ_SAN) -MMD -MP $(CFLAGS)
FUZZ_LIB_SRC := $(LIB_SRC) $(RENDER_SRC)
FUZZ_BIN     := $(FUZZ_NAMES:%=$(FUZZ_BUILD)/fuzz_%)
FUZZ_REPLAY  := $(FUZZ_NAMES:%=$(FUZZ_BUILD)/replay/fuzz_%)
FUZZ_REPLAY_RUN = for h in $(FUZZ_NAMES); do \
	  $(abspath $(FUZZ_BUILD))/replay/fuzz_$$h tests/fuzz/corpus/$$h \
	    $$(ls -d tests/fuzz/regressions/$$h 2>/dev/null) || exit 1; done
.PHONY: fuzz fuzz-replay fuzz-cc
fuzz: $(FUZZ_BIN)
fuzz-replay: $(FUZZ_REPLAY)
	@$(FUZZ_REPLAY_RUN)
fuzz-cc:
	@command -v $(FUZZ_CC) >/dev/null || { echo "make fuzz: '$(FUZZ_CC)' not found:" \
	  "install Debian packages clang and libclang-rt-14-dev (or set FUZZ_CC)"; exit 1; }

# library objects: libFuzzer build in lf/, replay build in replay/
$(FUZZ_BUILD)/lf/%.o: %.c $(BUILD)/.flags | fuzz-cc
	@mkdir -p $(@D)
	@$(if $(Q),echo '  CLANG   $<')
	$(Q)$(FUZZ_CC) $(FUZZ_CFLAGS) -fsanitize=fuzzer-no-link -c $< -o $@
$(FUZZ_BUILD)/replay/%.o: %.c $(BUILD)/.flags
	@mkdir -p $(@D)
	@$(if $(Q),echo '  CC      $<')
	$(Q)$(CC) $(FUZZ_CFLAGS) -c $< -o $@
$(FUZZ_BUILD)/lf/render/html.o $(FUZZ_BUILD)/replay/render/html.o: $(VIEWER_JS)
$(FUZZ_BUILD)/lf/libsandslide.a: $(FUZZ_LIB_SRC:%.c=$(FUZZ_BUILD)/lf/%.o)
	$(Q)rm -f $@ && ar rcs $@ $^
$(FUZZ_BUILD)/replay/libsandslide.a: $(FUZZ_LIB_SRC:%.c=$(FUZZ_BUILD)/replay/%.o)
	$(Q)rm -f $@ && ar rcs $@ $^
$(FUZZ_BUILD)/fuzz_%: tests/fuzz/fuzz_%.c $(FUZZ_BUILD)/lf/libsandslide.a $(wildcard tests/fuzz/*.h)
	@$(if $(Q),echo '  LINK    $@')
	$(Q)$(FUZZ_CC) $(filter-out -MMD -MP,$(FUZZ_CFLAGS)) -fsanitize=fuzzer $(filter %.c %.a,$^) $(LIBS) -o $@
$(FUZZ_BUILD)/replay/fuzz_%: tests/fuzz/fuzz_%.c tests/fuzz/replay.c $(FUZZ_BUILD)/replay/libsandslide.a $(wildcard tests/fuzz/*.h)
	@$(if $(Q),echo '  LINK    $@')
	$(Q)$(CC) $(filter-out -MMD -MP,$(FUZZ_CFLAGS)) $(filter %.c %.a,$^) $(LIBS) -o $@
# replay/render/x.d and replay/src/io/x.d: the tiers are one level deeper
-include $(wildcard $(FUZZ_BUILD)/*/*/*.d $(FUZZ_BUILD)/*/*/*/*.d)

# The man page: doc/sandslide.1.in, written by hand, with each command's
# options filled in by the program itself from the option tables it parses
# (`sandslide help --roff CMD`, the --help's walk written as roff), so that
# the page and --help cannot disagree; doc/manpage.awk puts them, and the
# template's notes on them, where the template's blocks say.  POSIX awk.
$(BUILD)/sandslide.1: doc/sandslide.1.in doc/manpage.awk $(BUILD)/sandslide
	@$(if $(Q),echo '  MAN     $@')
	$(Q)awk -v program=$(BUILD)/sandslide -f doc/manpage.awk doc/sandslide.1.in > $@

# The test hooks (tests/hooks/NAME_step.c): the command line linked again
# with the stepper's advance wrapped, as $(BUILD)/tests/sandslide-NAME, so
# that a test can put a NaN into a height (nan: the non-finite guard), or
# stop a run at a known substep until it is signalled (pause: the
# interrupt, without racing the run); or with its prepare wrapped, to
# shrink the outflow batch of a distributed run (batch: test-mpi only);
# the real sandslide has no hook.
HOOK_NAN   := $(BUILD)/tests/sandslide-nan
HOOK_PAUSE := $(BUILD)/tests/sandslide-pause
HOOK_BATCH := $(BUILD)/tests/sandslide-batch
HOOK_BIN   := $(HOOK_NAN) $(HOOK_PAUSE)
# `make` leaves them out (they are no part of what it installs); `make
# test` builds them, and so does `make test-hooks`, which tests/README.md's
# recipe for one CLI test file names
.PHONY: test-hooks
test-hooks: $(HOOK_BIN)
$(HOOK_BIN) $(HOOK_BATCH): $(BUILD)/tests/sandslide-%: tests/hooks/%_step.c $(MAIN_OBJ) \
             $(BUILD)/libsandslide.a $(BUILD)/.flags
	@mkdir -p $(@D)
	@$(if $(Q),echo '  LINK    $@')
	$(Q)$(CC) $(filter-out -MMD -MP,$(ALL_CFLAGS)) $< $(MAIN_OBJ) \
	  $(BUILD)/libsandslide.a $(ALL_LDFLAGS) \
	  -Wl,--wrap=$(if $(filter batch,$*),ss_stepper_prepare,ss_stepper_advance) $(LIBS) -o $@

# The Python module's tests load the library into python3: a sanitized one
# needs its run-time libraries loaded first, and Python's own allocations
# are not ours to report as leaks.
ifeq ($(SANITIZE),1)
  PY_PRELOAD = $$($(CC) -print-file-name=libasan.so) $$($(CC) -print-file-name=libubsan.so)
  PY_SAN_ENV = LD_PRELOAD="$(PY_PRELOAD)" ASAN_OPTIONS=detect_leaks=0:exitcode=86
endif

# The README's test command.  The layering check, the C test programs
# (each ends with "N passed, M failed", or with ", K skipped" after it
# when something was skipped, each skip saying why; a program or test
# function that made no check fails), the fuzz corpora replayed, then the
# CLI/file tests and the Python module's with pytest (-rs: every skip
# prints its reason).  test_mpi.py is left to test-mpi.  C_TESTS and
# CLI_TESTS name the C programs (their names: test_api ...) and the CLI
# test files (pytest's arguments; empty: none) to run, all of them by
# default; .ci/run narrows them where another part of CI runs the rest.
# PY_TESTS: the Python module's (pytest's arguments).
C_TESTS   ?= $(notdir $(TEST_BIN))
CLI_TESTS ?= tests/cli
PY_TESTS  ?= tests/python
test check: all $(TEST_BIN) test-hooks headers-check check-layering $(FUZZ_REPLAY)
	@fail=0; for t in $(addprefix $(BUILD)/tests/,$(C_TESTS)); do \
	  echo "== $$t"; OMP_NUM_THREADS=$${OMP_NUM_THREADS:-2} ./$$t || fail=1; \
	done; \
	echo "== tests/fuzz (corpora and regressions replayed)"; ( $(FUZZ_REPLAY_RUN) ) || fail=1; \
	[ -z "$(CLI_TESTS)" ] || echo "== tests/cli (pytest)"; \
	[ -z "$(CLI_TESTS)" ] || SANDSLIDE_MPI= SANDSLIDE=$(abspath $(BUILD)/sandslide) SANDSLIDE_NAN=$(abspath $(HOOK_NAN)) \
	  SANDSLIDE_PAUSE=$(abspath $(HOOK_PAUSE)) \
	  SANDSLIDE_MAKEFLAGS="BUILD=$(BUILD) SANITIZE=$(SANITIZE) MPI=$(MPI) OPENMP=$(OPENMP) GDAL=$(GDAL)" \
	  SANDSLIDE_CC="$(CC)" SANDSLIDE_LDFLAGS="$(ALL_LDFLAGS)" SANDSLIDE_PY_PRELOAD="$(PY_PRELOAD)" \
	  $(PYTHON) -m pytest -q -rs $(CLI_TESTS) --ignore=tests/cli/test_mpi.py || fail=1; \
	echo "== tests/python (pytest)"; \
	$(PY_SAN_ENV) SANDSLIDE=$(abspath $(BUILD)/sandslide) \
	  SANDSLIDE_LIBRARY=$(abspath $(BUILD)/$(SONAME)) PYTHONPATH=python \
	  $(PYTHON) -m pytest -q -rs $(PY_TESTS) || fail=1; \
	exit $$fail

# The distributed tests (make MPI=1 test-mpi): the C test of the halo and
# the ordered sums alone and under mpirun -np 1 .. 4, then
# tests/cli/test_mpi.py (which `make test` leaves out), which
# compares every snapshot of build-mpi/sandslide under np = 1..4 with the
# serial build/sandslide (built first), also with the pause and batch hooks.  Open MPI's settings for a root
# user, more ranks than cores, no RDMA (doc/cluster.md#open-mpi-as-root-on-a-small-machine).
MPI_ENV := OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 \
           OMPI_MCA_rmaps_base_oversubscribe=1 OMPI_MCA_mpi_yield_when_idle=1 \
           OMPI_MCA_btl_vader_single_copy_mechanism=none OMPI_MCA_pml=ob1 \
           OMPI_MCA_btl=self,vader OMPI_MCA_btl_base_warn_component_unused=0 OMP_NUM_THREADS=1
.PHONY: test-mpi
test-mpi: all $(BUILD)/tests/test_comm $(HOOK_PAUSE) $(HOOK_BATCH)
	@[ "$(MPI)" = 1 ] || { echo "test-mpi: run it as make MPI=1 test-mpi"; exit 2; }
	$(MAKE) MPI=0 all
	@echo "== $(BUILD)/tests/test_comm (alone, then mpirun -np 1 .. 4)"; \
	  $(MPI_ENV) timeout 120 $(BUILD)/tests/test_comm || exit 1; \
	  for n in 1 2 3 4; do \
	    $(MPI_ENV) timeout 120 mpirun.openmpi -np $$n --bind-to none $(BUILD)/tests/test_comm || exit 1; \
	  done
	@echo "== tests/cli/test_mpi.py (pytest)"; \
	  $(MPI_ENV) SANDSLIDE_MPI=$(abspath $(BUILD)/sandslide) SANDSLIDE=$(abspath build/sandslide) \
	  SANDSLIDE_MPI_PAUSE=$(abspath $(HOOK_PAUSE)) SANDSLIDE_MPI_BATCH=$(abspath $(HOOK_BATCH)) \
	  $(PYTHON) -m pytest -q -rs tests/cli/test_mpi.py

# The GPU backend's checks (make CUDA=1 test-cuda; doc/gpu.md), on any
# machine: the kernels' PTX has no fused multiply-add
# (tests/gpu/check_ptx.sh, with the build's nvcc flags), then
# tests/gpu/test_cuda (the device's loop against the CPU's generic path,
# bit for bit) and tests/gpu/test_gpu_bench.py (bench on the GPU, the CLI's
# refusals), whose GPU checks skip with the reason where there is no GPU;
# tests/cli/test_device.py with this build's binary.  On the GPU machine
# tools/gpu_check.sh runs it, and the measurements.
NVCC_PTX_FLAGS := -std=c++17 -O3 $(NVCC_FP) -arch=compute_$(firstword $(CUDA_ARCHS)) \
                  -Iinclude -Isrc -DSS_HAVE_CUDA
.PHONY: test-cuda
test-cuda: all $(BUILD)/tests/gpu/test_cuda
	@[ "$(CUDA)" = 1 ] || { echo "test-cuda: run it as make CUDA=1 test-cuda"; exit 2; }
	@echo "== tests/gpu/check_ptx.sh"; sh tests/gpu/check_ptx.sh $(NVCC) $(NVCC_PTX_FLAGS)
	@echo "== $(BUILD)/tests/gpu/test_cuda"; ./$(BUILD)/tests/gpu/test_cuda
	@echo "== tests/gpu, tests/cli/test_device.py (pytest)"; \
	  SANDSLIDE=$(abspath $(BUILD)/sandslide) \
	  $(PYTHON) -m pytest -q -rs tests/gpu tests/cli/test_device.py

# A real Slurm on this machine (make MPI=1 test-slurm; make deps-slurm
# installs it): tests/slurm/run.sh starts munged, slurmctld and slurmd as
# root, submits the job of doc/cluster.md#slurm (tests/slurm/job.sh) with
# sbatch --wait, as 2 tasks x 1 CPU and 1 task x 2 CPUs, and compares each
# output with the serial build/sandslide's (built first) bit for bit.
# About 10 s.  Not in `make test`: it needs root and starts daemons.
.PHONY: test-slurm
test-slurm: all
	@[ "$(MPI)" = 1 ] || { echo "test-slurm: run it as make MPI=1 test-slurm"; exit 2; }
	$(MAKE) MPI=0 all
	@echo "== tests/slurm/run.sh (sbatch --wait, srun --mpi=pmix)"; \
	  timeout 300 sh tests/slurm/run.sh $(BUILD)/sandslide build/sandslide

# The tiers of src/README.md, checked by the #includes of each file: the
# kernel knows nothing of files, printing or the command line, I/O nothing
# of the stencil, and only the io/h5 files (src/io/h5_*) include <hdf5.h>
# (tests/check_layering.sh).
check-layering:
	@sh tests/check_layering.sh

# ---- data races: make race (ThreadSanitizer + Archer) ----------------------
# The library, sandslide and the C tests built again with clang
# -fsanitize=thread against LLVM's libomp into RACE_BUILD, then
# tests/race.sh runs them on 2 threads (the C tests, and sandslide run with
# both kernels, relax, render, bench on small cases) with Archer, the OMPT
# tool of libomp that tells ThreadSanitizer about OpenMP's barriers and
# reductions, so that what it reports is a real race.  Any report fails;
# tests/tsan.supp says why it names libomp, Archer and GDAL.
# Debian packages: DEB_RACE.  -ffp-contract=off keeps clang from fusing
# a * b + c into FMAs, as gcc in C11 mode does not: the tests compare bits.
RACE_CC     ?= clang
RACE_BUILD  ?= build-race
RACE_CFLAGS := -fsanitize=thread -O1 -g -fno-omit-frame-pointer -ffp-contract=off
# CI runs it, so `make deps` installs them: 17 packages, 49 MB on a machine
# with the other dependencies.
DEB_RACE    := clang libclang-rt-dev libomp-dev
DEB_TEST    += $(DEB_RACE)
.PHONY: race
race:
	@command -v $(RACE_CC) >/dev/null || { echo "race: $(RACE_CC) not found: install Debian packages $(DEB_RACE)"; exit 1; }
	@archer=$$(dirname $$($(RACE_CC) -print-resource-dir))/../libarcher.so; \
	  [ -f "$$archer" ] || { echo "race: $$archer not found: install Debian packages $(DEB_RACE)"; exit 1; }
	$(MAKE) BUILD=$(RACE_BUILD) CC=$(RACE_CC) SANITIZE=0 OPENMP=1 \
	  CFLAGS="$(RACE_CFLAGS) $(CFLAGS)" LDFLAGS="-fsanitize=thread $(LDFLAGS)" \
	  $(RACE_BUILD)/sandslide $(TEST_BIN:$(BUILD)/%=$(RACE_BUILD)/%)
	@archer=$$(realpath $$(dirname $$($(RACE_CC) -print-resource-dir))/../libarcher.so); \
	  OMP_TOOL_LIBRARIES=$$archer SANDSLIDE_TEST_SCALE=$${SANDSLIDE_TEST_SCALE:-0.5} \
	  TSAN_OPTIONS="$${TSAN_OPTIONS:-exitcode=66 suppressions=$(abspath tests/tsan.supp)}" \
	  sh tests/race.sh $(RACE_BUILD)

# ---- make install / make uninstall -----------------------------------------
# The usual GNU variables: PREFIX (default /usr/local) and the folders under
# it, DESTDIR to stage the tree elsewhere (a package build, the install
# test).  The Python module goes where PREFIX's python3 looks: the entry of
# its sys.path under PREFIX/lib (Debian: /usr/local/lib/python3.X/
# dist-packages), else PREFIX/lib/python3.X/site-packages (then set
# PYTHONPATH); it is told where the installed library is (_library.py).
PREFIX      ?= /usr/local
BINDIR      ?= $(PREFIX)/bin
LIBDIR      ?= $(PREFIX)/lib
INCLUDEDIR  ?= $(PREFIX)/include
DATADIR     ?= $(PREFIX)/share
MANDIR      ?= $(DATADIR)/man
PKGCONFIGDIR ?= $(LIBDIR)/pkgconfig
PYTHONDIR   ?= $(shell $(PYTHON) -c 'import sys, sysconfig; p = "$(PREFIX)"; \
  c = [d for d in sys.path if d.startswith(p + "/lib/") and d.endswith("-packages")]; \
  print(c[0] if c else sysconfig.get_path("purelib", "posix_prefix", {"base": p, "platbase": p}))')
INSTALL     ?= install
INSTALL_HEADERS := $(HEADERS)
PY_SRC      := $(wildcard python/sandslide/*.py)
PC_REQUIRES := $(PC_MODULES)$(if $(findstring SS_HAVE_GDAL,$(DEP_CFLAGS)), gdal)

install: all
	$(INSTALL) -d $(DESTDIR)$(BINDIR) $(DESTDIR)$(LIBDIR) $(DESTDIR)$(INCLUDEDIR)/sandslide \
	  $(DESTDIR)$(PKGCONFIGDIR) $(DESTDIR)$(MANDIR)/man1 $(DESTDIR)$(DATADIR)/sandslide/cases/dem \
	  $(DESTDIR)$(PYTHONDIR)/sandslide
	$(INSTALL) -m 755 $(BUILD)/sandslide $(DESTDIR)$(BINDIR)/sandslide
	$(INSTALL) -m 755 $(BUILD)/$(SHLIB) $(DESTDIR)$(LIBDIR)/$(SHLIB)
	ln -sf $(SHLIB) $(DESTDIR)$(LIBDIR)/$(SONAME)
	ln -sf $(SONAME) $(DESTDIR)$(LIBDIR)/libsandslide.so
	$(INSTALL) -m 644 $(BUILD)/libsandslide.a $(DESTDIR)$(LIBDIR)/libsandslide.a
	$(INSTALL) -m 644 $(INSTALL_HEADERS) $(DESTDIR)$(INCLUDEDIR)/sandslide/
	sed -e 's|@PREFIX@|$(PREFIX)|' -e 's|@LIBDIR@|$(patsubst $(PREFIX)/%,$${prefix}/%,$(LIBDIR))|' -e 's|@INCLUDEDIR@|$(patsubst $(PREFIX)/%,$${prefix}/%,$(INCLUDEDIR))|' \
	  -e 's|@VERSION@|$(VERSION)|' \
	  -e 's|@REQUIRES@|$(PC_REQUIRES)|' -e 's|@OPENMP@|$(filter -fopenmp,$(OMPFLAG))|' \
	  sandslide.pc.in > $(DESTDIR)$(PKGCONFIGDIR)/sandslide.pc
	$(INSTALL) -m 644 $(BUILD)/sandslide.1 $(DESTDIR)$(MANDIR)/man1/sandslide.1
	$(INSTALL) -m 644 $(wildcard cases/*.ini cases/*.py) $(DESTDIR)$(DATADIR)/sandslide/cases/
	$(INSTALL) -m 644 $(wildcard cases/dem/*) $(DESTDIR)$(DATADIR)/sandslide/cases/dem/
	$(if $(PY_SRC),$(INSTALL) -m 644 $(PY_SRC) $(DESTDIR)$(PYTHONDIR)/sandslide/)
	printf '# written by make install: the library this module loads\nPATH = "%s"\n' \
	  '$(LIBDIR)/$(SONAME)' > $(DESTDIR)$(PYTHONDIR)/sandslide/_library.py
	@# the loader's cache, for a system folder (root, no DESTDIR)
	@[ -n "$(DESTDIR)" ] || [ "$$(id -u)" != 0 ] || ! command -v ldconfig >/dev/null || ldconfig
	@echo "installed sandslide $(VERSION) under $(DESTDIR)$(PREFIX) (Python module in $(DESTDIR)$(PYTHONDIR))"

uninstall:
	rm -f $(DESTDIR)$(BINDIR)/sandslide $(DESTDIR)$(LIBDIR)/$(SHLIB) $(DESTDIR)$(LIBDIR)/$(SONAME) \
	  $(DESTDIR)$(LIBDIR)/libsandslide.so $(DESTDIR)$(LIBDIR)/libsandslide.a \
	  $(DESTDIR)$(PKGCONFIGDIR)/sandslide.pc $(DESTDIR)$(MANDIR)/man1/sandslide.1 \
	  $(HEADERS:include/sandslide/%=$(DESTDIR)$(INCLUDEDIR)/sandslide/%)
	rm -rf $(DESTDIR)$(DATADIR)/sandslide $(DESTDIR)$(PYTHONDIR)/sandslide
	-rmdir $(DESTDIR)$(INCLUDEDIR)/sandslide 2>/dev/null

demo: all
	@mkdir -p out
	./$(BUILD)/sandslide run cases/door.ini -o out/demo.h5 --force

# `make deps`: what building and running need (DEB_BUILD, DEB_RUN, and
# with MPI=1 Open MPI); `make deps-test`: what the test suite adds
# (DEB_TEST: pytest, the readers the output is checked with, ParaView,
# clang); `make deps-bench`: the benchmarks' real DEMs (DEB_BENCH);
# `make deps-slurm`: Slurm and munge (DEB_SLURM).  apt-get only for what
# is missing.
DEPS_INSTALL = missing=""; for p in $(1); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q 'ok installed' || missing="$$missing $$p"; \
	done; \
	if [ -z "$$missing" ]; then echo "$@: all Debian packages present ($(strip $(1)))"; \
	else \
	  echo "$@: installing missing Debian packages:$$missing"; \
	  SUDO=""; [ "$$(id -u)" = 0 ] || SUDO=sudo; \
	  $$SUDO apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq --no-install-recommends $$missing; \
	fi
deps:
	@$(call DEPS_INSTALL,$(DEB_BUILD) $(DEB_RUN))
deps-test: deps
	@$(call DEPS_INSTALL,$(DEB_TEST))
deps-bench: deps
	@$(call DEPS_INSTALL,$(DEB_BENCH))
deps-slurm: deps
	@$(call DEPS_INSTALL,$(DEB_SLURM))

clean:
	rm -rf $(BUILD)

help:
	@sed -n '3,/^#$$/{/^#$$/!p}' Makefile | sed 's/^# \{0,1\}//'

-include $(LIB_OBJ:.o=.d) $(MAIN_OBJ:.o=.d) $(TEST_BIN:=.d)
