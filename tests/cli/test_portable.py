# SPDX-License-Identifier: BSD-3-Clause
"""A portable build (include/sandslide/cpu.h, Makefile NATIVE): the default
build runs on any x86-64 processor, and chooses at run time the best copy
of the kernel's hot loops the processor runs (generic, avx2, avx512);
SANDSLIDE_CPU forces one.

  version          --version names the path in use: the best this processor
                   runs (from /proc/cpuinfo), or the one SANDSLIDE_CPU forces
  refusals         an unknown SANDSLIDE_CPU, or a path the processor lacks,
                   exits 2 naming the variable (the second is skipped on a
                   processor that runs every path)
  forced paths     on every path the processor runs: the cone relaxes to the
                   repose angle with its volume kept; the fast kernel on 1
                   and 2 threads and the reference kernel give the same
                   bits; the generic and avx2 paths give the same bits, the
                   avx512 path others; bench names the reciprocal square
                   root truthfully
  machine code     outside the copies compiled for AVX2 and AVX-512 (the
                   members FILE-avx2.o and FILE-avx512.o of libsandslide.a),
                   no instruction beyond the x86-64 baseline (SSE2) in the
                   library, the shared library or the program: no VEX or
                   EVEX encoding, no ymm, zmm or mask register, no SSE3 to
                   SSE4.2, POPCNT, LZCNT, BMI, MOVBE or ADX; and the AVX-512
                   copy does use AVX-512 (the check sees it).  Skipped for a
                   NATIVE=1 build and on another processor than x86-64.
"""
import os
import platform
import re
import shutil
import subprocess

import numpy as np
import pytest

from conftest import CASES, SANDSLIDE, h5open, run, same_bits

BUILD = os.path.dirname(SANDSLIDE)
PATHS = ["generic", "avx2", "avx512"]


def cpu_flags():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("flags"):
                    return set(line.split(":", 1)[1].split())
    except OSError:
        pass
    return set()


def paths_this_processor_runs():
    """The paths cpu.c accepts, from the flags the kernel reports (which,
    like the compiler's check, include the operating system's support)."""
    if platform.machine() != "x86_64":
        return ["generic"]
    flags = cpu_flags()
    out = ["generic"]
    if {"avx2", "popcnt"} <= flags:
        out.append("avx2")
        if {"avx512f", "avx512cd", "avx512vl", "avx512bw", "avx512dq"} <= flags:
            out.append("avx512")
    return out


RUNS = paths_this_processor_runs()


def sandslide(args, cwd=None, cpu=None, timeout=300):
    env = {k: v for k, v in os.environ.items() if k != "SANDSLIDE_CPU"}
    if cpu is not None:
        env["SANDSLIDE_CPU"] = cpu
    return run(args, cwd=cwd, env=env, timeout=timeout)


def kernel_of(version_line):
    m = re.search(r"kernel: (\w+)", version_line)
    assert m, f"--version does not name the kernel path: {version_line!r}"
    return m.group(1)


def test_version_names_the_path():
    r = sandslide(["--version"])
    assert r.returncode == 0, r.stderr
    assert kernel_of(r.stdout) == RUNS[-1], \
        f"by default the best path this processor runs ({RUNS[-1]}): {r.stdout!r}"
    for path in RUNS + ["auto", ""]:
        r = sandslide(["--version"], cpu=path)
        assert r.returncode == 0, f"SANDSLIDE_CPU={path!r}: {r.stderr}"
        want = RUNS[-1] if path in ("auto", "") else path
        assert kernel_of(r.stdout) == want, f"SANDSLIDE_CPU={path!r}: {r.stdout!r}"


def test_an_unknown_path_is_refused(tmp_path):
    for args in (["--version"], ["run", os.path.join(CASES, "cone.ini"), "-o",
                                 str(tmp_path / "c.h5")]):
        r = sandslide(args, cpu="avx1024")
        assert r.returncode == 2, f"SANDSLIDE_CPU=avx1024 {args[0]}: exit {r.returncode}"
        assert "SANDSLIDE_CPU=avx1024" in r.stderr and "generic" in r.stderr, r.stderr
        assert not (tmp_path / "c.h5").exists(), "a run went ahead with a refused path"


def test_a_path_the_processor_lacks_is_refused():
    lacking = [p for p in PATHS if p not in RUNS]
    if not lacking:
        pytest.skip("this processor runs every path: no path to refuse")
    for path in lacking:
        r = sandslide(["--version"], cpu=path)
        assert r.returncode == 2, f"SANDSLIDE_CPU={path} on a processor without it: " \
            f"exit {r.returncode}"
        assert f"SANDSLIDE_CPU={path}" in r.stderr and "cannot run" in r.stderr, r.stderr


# ---- every path runs the physics -----------------------------------------

def cone(tmp_path, name, cpu, *extra):
    """cases/cone.ini (Coulomb, a 50 degree cone relaxing to 35 degrees) on
    41 x 41 cells of 6 cm, with forward Euler, on the path cpu: steady by
    t = 20 s (2000 steps).  Returns the output's path."""
    out = tmp_path / f"{name}.h5"
    r = sandslide(["run", os.path.join(CASES, "cone.ini"), "-o", out, "-q",
                   "--set", "grid.nx=41", "--set", "grid.ny=41", "--set", "grid.dx=0.06",
                   "--set", "time.integrator=euler", *extra], cpu=cpu)
    assert r.returncode == 0, f"SANDSLIDE_CPU={cpu} {name}: {r.stderr}"
    return out


def assert_same_output(a, b, what):
    with h5open(a) as fa, h5open(b) as fb:
        assert same_bits(fa["time"][:], fb["time"][:]), f"{what}: the times differ"
        ha, hb = fa["height"][:], fb["height"][:]
        assert same_bits(ha, hb), f"{what}: the heights differ (max |dh| " \
            f"{np.abs(ha - hb).max()!r} m)"


@pytest.fixture(scope="module")
def cones(tmp_path_factory):
    """{path: the cone on 2 threads} for the paths this processor runs."""
    d = tmp_path_factory.mktemp("cones")
    return {path: cone(d, path, path, "--threads", "2") for path in RUNS}


@pytest.mark.parametrize("path", PATHS)
def test_each_path_relaxes_the_cone(tmp_path, cones, path):
    if path not in RUNS:
        pytest.skip(f"this processor cannot run the {path} path")
    two = cones[path]
    with h5open(two) as f:
        vol = f["volume"][:]
        slope = f["max_slope_deg"][:]
        t = f["time"][:]
    assert t[-1] < 300, f"{path}: the cone did not come to rest before max_time ({t[-1]} s)"
    assert abs(vol[-1] - vol[0]) <= 1e-12 * vol[0], \
        f"{path}: the volume changed from {vol[0]!r} to {vol[-1]!r} m^3"
    assert 34.0 < slope[-1] < 35.1, \
        f"{path}: the cone at rest is at {slope[-1]} deg, not the 35 deg repose angle"
    one = cone(tmp_path, "one", path, "--threads", "1")
    assert_same_output(one, two, f"{path} path, 1 against 2 threads")
    ref = cone(tmp_path, "ref", path, "--threads", "1", "--reference-kernel")
    assert_same_output(ref, two, f"{path} path, the reference against the fast kernel")


def test_generic_and_avx2_give_the_same_bits(cones):
    if "avx2" not in RUNS:
        pytest.skip("this processor cannot run the avx2 path")
    assert_same_output(cones["generic"], cones["avx2"], "the generic against the avx2 path")


def test_avx512_gives_its_own_bits(cones):
    """Not a property of the physics but of the test: a forced path is the
    one that runs (the AVX-512 reciprocal square root rounds otherwise)."""
    if "avx512" not in RUNS:
        pytest.skip("this processor cannot run the avx512 path")
    with h5open(cones["generic"]) as fg, h5open(cones["avx512"]) as fa:
        assert not same_bits(fg["height"][:], fa["height"][:]), \
            "SANDSLIDE_CPU=generic and avx512 give the same bits: is the path forced?"


def test_bench_names_the_reciprocal_square_root():
    for path in RUNS:
        r = sandslide(["bench", "--nx", "600", "--ny", "600", "--closure", "coulomb",
                       "--surface", "patch", "--threads", "1", "--repeats", "1",
                       "--steps", "2"], cpu=path)
        assert r.returncode == 0, r.stderr
        want = "vrsqrt14pd" if path == "avx512" else "1/sqrt"
        assert f"reciprocal sqrt: {want}" in r.stdout, f"SANDSLIDE_CPU={path}: {r.stdout}"


# ---- the machine code ----------------------------------------------------

# Beyond the x86-64 baseline without a VEX or EVEX encoding (AT&T names as
# objdump prints them).  Not listed: tzcnt, which is how objdump shows the
# `rep bsf` gcc emits for any x86-64 (it runs as bsf where TZCNT is
# missing), and cpuid and xgetbv, with which the compiler's run-time library
# asks the processor what it has.
NOT_BASELINE = set("""
addsubpd addsubps haddpd haddps hsubpd hsubps lddqu movddup movshdup movsldup
pabsb pabsw pabsd palignr phaddw phaddd phaddsw phsubw phsubd phsubsw pmaddubsw
pmulhrsw pshufb psignb psignw psignd
blendpd blendps blendvpd blendvps dppd dpps extractps insertps movntdqa mpsadbw
packusdw pblendvb pblendw pcmpeqq pextrb pextrd pextrq phminposuw pinsrb pinsrd
pinsrq pmaxsb pmaxsd pmaxud pmaxuw pminsb pminsd pminud pminuw pmovsxbw pmovsxbd
pmovsxbq pmovsxwd pmovsxwq pmovsxdq pmovzxbw pmovzxbd pmovzxbq pmovzxwd pmovzxwq
pmovzxdq pmuldq pmulld ptest roundpd roundps roundsd roundss
pcmpestri pcmpestrm pcmpistri pcmpistrm pcmpgtq crc32b crc32w crc32l crc32q
popcnt lzcnt andn bextr blsi blsmsk blsr bzhi mulx pdep pext rorx sarx shlx shrx
movbe adcx adox
""".split())
PREFIXES = {"rep", "repz", "repe", "repnz", "repne", "lock", "notrack", "bnd", "data16",
            "addr32", "cs", "ds", "ss", "es", "fs", "gs", "rex", "rex.W"}
WIDE_REGISTER = re.compile(r"%(?:[yz]mm\d+|k[0-7]\b)")


def beyond_baseline(mnemonic, operands):
    if WIDE_REGISTER.search(operands):
        return True
    if mnemonic.startswith("v") and mnemonic not in ("verr", "verw"):
        return True
    return mnemonic in NOT_BASELINE or mnemonic.rstrip("bwlq") in NOT_BASELINE


AVX512 = re.compile(r"%zmm|%k[0-7]\b|14p[sd]\b")


def functions_beyond_baseline(path):
    """Over the disassembly of an object, archive or linked file:
    {(member or None, function): its first instruction beyond the baseline},
    the set of every (member, function), and the set of those that use
    AVX-512 (zmm or mask registers, vrsqrt14pd)."""
    out = subprocess.run(["objdump", "-d", "--no-show-raw-insn", path], capture_output=True,
                         text=True, check=True).stdout
    member, function, found, every, avx512 = None, None, {}, set(), set()
    for line in out.splitlines():
        m = re.match(r"^(\S+\.o):\s+file format", line)
        if m:
            member = os.path.basename(m.group(1))
            continue
        m = re.match(r"^[0-9a-f]+ <(.+)>:$", line)
        if m:
            function = m.group(1)
            every.add((member, function))
            continue
        m = re.match(r"^\s*[0-9a-f]+:\s+(.*)$", line)
        if not m or function is None:
            continue
        words = m.group(1).split()
        while words and words[0] in PREFIXES:
            words = words[1:]
        if not words:
            continue
        operands = " ".join(words[1:])
        if (member, function) not in found and beyond_baseline(words[0], operands):
            found[(member, function)] = m.group(1).strip()
        if AVX512.search(words[0] + " " + operands):
            avx512.add((member, function))
    return found, every, avx512


def path_member(member):
    return member is not None and re.search(r"-(avx2|avx512)\.o$", member) is not None


@pytest.fixture(scope="module")
def build_files():
    if platform.machine() != "x86_64":
        pytest.skip("the baseline checked is x86-64's")
    if not shutil.which("objdump"):
        pytest.skip("objdump not found (Debian package binutils)")
    archive = os.path.join(BUILD, "libsandslide.a")
    shared = os.path.join(BUILD, "libsandslide.so")
    if not (os.path.isfile(archive) and os.path.isfile(shared)):
        pytest.skip(f"no libsandslide.a and libsandslide.so beside {SANDSLIDE}")
    try:
        with open(os.path.join(BUILD, ".flags")) as f:
            if "-march=native" in f.read():
                pytest.skip("a NATIVE=1 build is for the machine that built it")
    except OSError:
        pass
    return archive, shared, SANDSLIDE


def test_only_the_path_copies_go_beyond_the_baseline(build_files):
    archive, shared, program = build_files
    found, every, avx512 = functions_beyond_baseline(archive)
    members = {m for m, _ in every}
    assert any(path_member(m) for m in members), \
        f"libsandslide.a has no member FILE-avx2.o or FILE-avx512.o: {sorted(members)}"
    outside = {k: v for k, v in found.items() if not path_member(k[0])}
    assert not outside, "beyond the x86-64 baseline outside the AVX2 and AVX-512 copies:\n" + \
        "\n".join(f"  {m}: {fn}: {insn}" for (m, fn), insn in sorted(outside.items()))
    # the detector sees AVX-512 where it is: not a vacuous check
    assert ("face-avx512.o", "ss_face_fluxes_avx512") in avx512, \
        "ss_face_fluxes_avx512 (face-avx512.o) uses no AVX-512: the check sees nothing"
    allowed = {fn for m, fn in every if path_member(m)}
    for linked in (shared, program):
        found_l, _, avx512_l = functions_beyond_baseline(linked)
        stray = {fn: insn for (_, fn), insn in found_l.items() if fn not in allowed}
        assert not stray, f"{os.path.basename(linked)}: beyond the x86-64 baseline in " \
            "functions of no AVX2 or AVX-512 copy:\n" + \
            "\n".join(f"  {fn}: {insn}" for fn, insn in sorted(stray.items()))
        assert (None, "ss_face_fluxes_avx512") in avx512_l, \
            f"{os.path.basename(linked)}: ss_face_fluxes_avx512 is missing or uses no AVX-512"
