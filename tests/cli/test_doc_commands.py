# SPDX-License-Identifier: BSD-3-Clause
"""The commands of the README and the manual run, in order, in a fresh copy
of the checkout, and print the figures the pages show beside them; so do
the commands in the shipped cases' headers.

tests/README.md#the-commands-of-the-docs says the same, for readers:

- The pages: README.md, then doc/*.md in the order of doc/README.md's
  table, then tests/README.md; each page's commands in their order, all in
  one copy of the checkout (the files git lists, as they are in the working
  tree, and the build as `make` leaves it, without build/tests/: a fresh
  clone after `make`), with its build/ first on PATH, then the folder of
  this Python.  The `command:` line of each cases/*.ini header runs in a
  second copy, its `runtime:` lines taken as its comment.
- A command is a line of an indented code block or of a sh, shell, bash
  or console fence (a line ending in a backslash goes on in the next)
  whose first word, after `$ ` and `NAME=value` settings, is one of
  RUNNERS.  Other lines (formulas, case-file lines, messages, Python) are
  not commands; neither is code in running text: a page that wants a
  command run puts it in a block.
- A ```python fence runs as `PYTHONPATH=python python3 -` with its code,
  in its place among the page's commands.
- A block with a synopsis, a command holding `[...]` (options) or `a|b`
  (a choice), shows a form: none of it runs.
- The parts of a command joined by `&&` are checked one by one against
  SKIP: a part left out is left out with its reason, the rest runs.  A
  command that needs what is missing (REQUIRES) is left out, saying so.
- SHORTEN rewrites the runs that take minutes; SANDSLIDE_DOC_FULL=1 runs
  every command as written.  The figures of a shortened or left-out
  command, and of the commands after it in its block, are not checked.
- Every command runs with SANDSLIDE_CPU=generic (the kernel every x86-64
  runs, whose counts the pages give: AVX-512 rounds differently,
  doc/model.md#builds-and-processors), OMP_NUM_THREADS=2,
  OMP_WAIT_POLICY=passive, and must exit 0.

The figures:

- Under a command written `$ ...`, the lines it prints (all or some, in
  order): each must be printed with the same text and numbers, but for
  measurements (MEASURED_BEFORE, MEASURED_AFTER): seconds (`wall X s`,
  `slope`, `sweep`, `output`, `read`, `write`, `in X s`), rates
  (`X .../s`) and memory (`peak X MiB`).
- In a command's comment, `N snapshots`, `N frames`, `N steps`,
  `N super-steps` and `N (stencil) evaluations` must be printed by it so,
  and `in N s` or `about N s` (or `min`) is its wall time.
- A measurement more than 3 times off (either way) is a warning in
  pytest's summary: machines differ, and CI's is shared (under load a
  2-thread run of a small case has been ten times slower: tests/README.md#ci);
  more than 30 times off fails, as no machine explains that.  Times under
  0.5 s are not compared.
"""
import functools
import glob
import os
import re
import shutil
import subprocess
import sys
import time
import warnings

import pytest

from conftest import ROOT, SANDSLIDE

# what `make` builds in build/ (besides obj/, gen/ and the libraries)
MADE_BY_MAKE = {"sandslide", "sandslide.1", ".flags"}
FULL = os.environ.get("SANDSLIDE_DOC_FULL", "") not in ("", "0")
WARN_RATIO = 3.0
FAIL_RATIO = 30.0

RUNNERS = re.compile(r"^(sandslide|\./build/sandslide|make|python3|/usr/bin/python3|tools/\S+|"
                     r"python/examples/\S+|cc|nice|/usr/bin/time|mpirun|srun|sudo|gdaldem)$")
ASSIGN = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*=")
FENCES = {"sh", "shell", "bash", "console"}

# (pattern searched in one part of a command, why it is left out)
SKIP = [
    (r"^make (deps|deps-test|deps-bench|deps-slurm)\b|apt-get",
     "installs Debian packages (root, network): CI's .ci/run does it first"),
    (r"^make( -j\d+)? (test|check)$|^make SANITIZE=1 test|^make race$",
     "the test suite itself: CI runs each part (.ci/run)"),
    (r"\bMPI=1\b|^mpirun|^srun|build-mpi/",
     "MPI: `make MPI=1 test-mpi` and `make MPI=1 test-slurm` run the distributed commands "
     "(tests/README.md#mpi)"),
    (r"^make (install|uninstall)\b",
     "writes outside the checkout (PREFIX): tests/cli/test_install.py installs into a DESTDIR"),
    (r"^cc prog\.c",
     "the reader's own program, against an installed sandslide: tests/cli/test_install.py "
     "builds tests/install/relax_dem.c both ways"),
    (r"-m venv|\.venv/",
     "pip into a virtual environment: tests/python/test_pip.py does it, offline"),
    (r'"scan\.h5"',
     "a fit to the reader's observations (scan.h5): tests/python/test_module.py fits a twin"),
    (r'gdal\.Open\("terrain\.tif"\)',
     "the reader's own GeoTIFF (terrain.tif): python/examples/relax_dem.py, run above, "
     "does the same with cases/dem/terrain.asc"),
    (r"tools/busy_bench\.py",
     "a benchmark of minutes with two busy loops beside it, measured against another "
     "checkout (DIR): run by hand"),
    (r"\bCUDA=1\b|tools/gpu_check\.sh|--device cuda",
     "the GPU backend: `make CUDA=1 test-cuda` builds and checks it (CI), "
     "tools/gpu_check.sh runs it on a GPU machine (doc/gpu.md)"),
    (r"--dems DIR\b",
     "the real DEMs of `make deps-bench` (R's and OpenFOAM's packages, not in CI; "
     "tools/real_dems.py writes them to DIR)"),
]

# (pattern of a command, what it needs, a test of it): left out, saying
# so, where it is missing (as the other tests skip without their tools)
REQUIRES = [
    (r"\.tif\b", "a build with GDAL", lambda: build_has("GDAL")),
    (r"--video\b", "ffmpeg", lambda: shutil.which("ffmpeg") is not None),
    (r"^gdaldem ", "gdaldem (gdal-bin)", lambda: shutil.which("gdaldem") is not None),
    (r"relax_dem\.py", "GDAL's Python bindings (python3-gdal)", lambda: importable("osgeo")),
    (r"wind_deposition\.py .*--png", "matplotlib (python3-matplotlib)",
     lambda: importable("matplotlib")),
    (r"-m pytest", "pytest", lambda: importable("pytest")),
    (r"sandslide\.open\(", "xarray with netCDF4 (python3-xarray, python3-netcdf4)",
     lambda: importable("xarray") and importable("netCDF4")),
    (r"\.plot\(", "matplotlib (python3-matplotlib)", lambda: importable("matplotlib")),
]

# (pattern of a command, [(regex, replacement), ...] applied to it, why):
# unless SANDSLIDE_DOC_FULL=1.
SHORTEN = [
    (r"^(\./build/)?sandslide bench$",
     [(r"$", " --nx 1024 --ny 1024 --repeats 1 --steps 2")],
     "8192^2 cells (GBs), every closure, 5 timings each: 1024^2, one timing of 2 steps"),
    (r"^(\./build/)?sandslide bench --nx",
     [(r"$", " --repeats 1 --steps 2")], "one timing of 2 steps"),
    (r"^sandslide run cases/door\.ini -o out/door480\.h5",
     [(r"$", " --set time.end=2")], "the door at 480 x 320 to 1000 s: 52 min; to 2 s"),
    (r"^sandslide run cases/door\.ini .*time\.integrator=euler$",
     [(r"$", " --set time.end=10")], "the door on Euler: half a minute; to 10 s"),
    (r"tools/time_to_solution\.py",
     [(r"$", " --dry")], "a benchmark of hours: its commands printed (--dry)"),
    (r"tools/fit_twin\.py",
     [(r"$", " --nx 21 --times 2,5")], "a search of 8 and 24 s: a 21 x 21 cone, two times"),
    (r"-m pytest -q tests/python$",
     [(r"tests/python$", "tests/python/test_module.py::test_version")],
     "the Python module's whole suite (`make test` runs it): one test of it"),
    (r"-m pytest -q tests/cli/test_relax\.py$",
     [(r"test_relax\.py$", "test_relax.py::test_cliff_relaxes_to_repose_with_volume_conserved")],
     "a CLI test file (`make test` runs it): one test of it"),
    # ffmpeg's H.264 encoding of 101 frames is half of the README's time:
    # the video of the columns (doc/rendering.md), whose frame count and
    # rate the test checks, is made in full
    (r"^sandslide run cases/door\.ini -o room\.h5 && sandslide render room\.h5 --video",
     [(r"--video", "--frames ::20 --video")], "a video of 101 frames: of 6"),
    (r"^sandslide render out/door\.h5 -o frames --video",
     [(r"--video", "--frames ::20 --video")], "a video of 101 frames: of 6"),
    (r"^sandslide run cases/columns\.ini -o out/columns-live\.h5 --frames",
     [(r"$", " --set time.end=200")], "85 frames drawn as it runs: 21, to 200 s"),
    (r"cases/fractal_dem\.py (4096|8192)",
     [(r" (4096|8192) ", " 256 ")], "a 4096^2 or 8192^2 terrain, relaxed in a minute: 256^2"),
    (r"^sandslide run cases/door\.ini -o out/door240\.h5 --threads 1",
     [(r"time\.end=300", "time.end=20")], "the door at 240 x 160 to 300 s: 20 s of wall time; to 20 s"),
]

# Measurements in a command's output: the number is preceded by one of
# these words, or followed by a rate's unit.
MEASURED_BEFORE = re.compile(r"(?:\bwall|\bslope|\bsweep|\boutput|\bread|\bwrite|\bin|\bpeak) $")
MEASURED_AFTER = re.compile(r"^ ?[\w.-]*/s\b|^ ?MiB\b|^ ?GiB\b|^ counting every\b")
SECONDS_AFTER = re.compile(r"^ ?s\b")
NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")
COUNT_WORDS = r"snapshots|frames|super-steps|steps|stencil evaluations|evaluations"
COMMENT_COUNT = re.compile(r"(?<![\w.^])(\d+) (" + COUNT_WORDS + r")\b")
COMMENT_TIME = re.compile(r"\b(?:in|about) (\d+(?:\.\d+)?) (s|min)\b(?!/)")


def pages():
    """README.md, doc/*.md in the order of the manual's index, tests/README.md."""
    with open(os.path.join(ROOT, "doc", "README.md")) as f:
        index = re.findall(r"^\| \[[^\]]+\]\(([\w-]+\.md)\)", f.read(), re.M)
    rest = sorted(os.path.basename(p) for p in glob.glob(os.path.join(ROOT, "doc", "*.md")))
    order = [p for p in index if p in rest] + [p for p in rest if p not in index and p != "README.md"]
    return ["README.md"] + ["doc/" + p for p in order] + ["tests/README.md"]


def code_blocks(text):
    """(line number, [lines]) of each indented block and shell fence."""
    lines = text.split("\n")
    out = []
    fence = None
    block = None
    previous_blank = True
    for number, line in enumerate(lines, 1):
        stripped = line.lstrip()
        if fence is not None:
            if stripped.startswith(fence[0]):
                if fence[1] in FENCES:
                    out.append((fence[2], block))
                fence = None
                block = None
            else:
                block.append(line[fence[3]:] if line[:fence[3]].strip() == "" else line)
            continue
        if stripped.startswith("```") or stripped.startswith("~~~"):
            if block is not None and fence is None:
                out.append((block_start, block))
                block = None
            indent = len(line) - len(stripped)
            fence = (stripped[:3], stripped[3:].strip().split(" ")[0], number + 1, indent)
            block = []
            continue
        blank = not line.strip()
        # an indented block: after a blank line, indented 4 more than the
        # text it sits in (a list item's text is indented by 2)
        indent = len(line) - len(stripped)
        if block is not None:
            if blank:
                block.append("")
                continue
            if indent >= block_indent:
                block.append(line[block_indent:])
                continue
            out.append((block_start, block))
            block = None
        if not blank and previous_blank and indent >= 4 and not stripped.startswith(("-", "*", "|")):
            block_indent = indent
            block_start = number
            block = [line[indent:]]
            previous_blank = False
            continue
        previous_blank = blank
    if block is not None and fence is None:
        out.append((block_start, block))
    return [(n, b) for n, b in out if any(x.strip() for x in b)]


def strip_comment(line):
    """(command, comment) split at a ` #` outside quotes."""
    quote = None
    for k, ch in enumerate(line):
        if quote:
            if ch == quote:
                quote = None
        elif ch in "'\"":
            quote = ch
        elif ch == "#" and (k == 0 or line[k - 1] in " \t"):
            return line[:k].rstrip(), line[k + 1:].strip()
    return line.rstrip(), ""


def first_word(command):
    words = command.split()
    while words and ASSIGN.match(words[0]):
        words.pop(0)
    return words[0] if words else ""


def is_synopsis(command):
    bare = re.sub(r"'[^']*'|\"[^\"]*\"|\$\([^)]*\)", "", command)
    return "[" in bare or re.search(r"\w\|\w", bare) is not None


class Command:
    def __init__(self, page, line, text, comment, expected, block=None):
        self.page, self.line, self.text, self.comment = page, line, text, comment
        self.block = (page, block)    # the commands of one block: (page, its first line)
        self.expected = expected      # lines shown under a `$ ` command
        self.skipped = []             # (part, why)
        self.shortened = None         # why
        self.run = self.plan()

    def where(self):
        return f"{self.page}:{self.line}"

    def plan(self):
        parts = [p.strip() for p in self.text.split("&&")]
        kept = []
        for part in parts:
            why = next((w for pat, w in SKIP if re.search(pat, part)), None)
            if why:
                self.skipped.append((part, why))
            else:
                kept.append(part)
        command = " && ".join(kept)
        if command and not FULL:
            for pat, edits, why in SHORTEN:
                if re.search(pat, command):
                    for old, new in edits:
                        command = re.sub(old, new, command, count=1)
                    self.shortened = why
                    break
        return command


def commands_of(page):
    """The commands of a page, in order."""
    with open(os.path.join(ROOT, page), encoding="utf-8") as f:
        text = f.read()
    out = []
    for start, block in code_blocks(text):
        session = any(l.startswith("$ ") for l in block)
        logical = []          # (line number, text, is command)
        k = 0
        while k < len(block):
            number = start + k
            line = block[k]
            if session and not line.startswith("$ "):
                logical.append((number, line, False))
                k += 1
                continue
            if session:
                line = line[2:]
            while line.rstrip().endswith("\\") and k + 1 < len(block):
                k += 1
                line = line.rstrip()[:-1].rstrip() + " " + block[k].strip()
            logical.append((number, line, True))
            k += 1
        candidates = []
        for number, line, is_command in logical:
            if not is_command:
                if candidates and line.strip():
                    candidates[-1][3].append(line)
                continue
            command, comment = strip_comment(line)
            if not command or not RUNNERS.match(first_word(command)):
                continue
            candidates.append([number, command, comment, []])
        if any(is_synopsis(c[1]) for c in candidates):
            continue
        out += [Command(page, n, c, m, e, start) for n, c, m, e in candidates]
    # Python fences run too, as a reader pastes them into python3 in the
    # checkout (PYTHONPATH=python), in their place among the commands
    for start, code in python_blocks(text):
        out.append(Command(page, start, "PYTHONPATH=python python3 - <<'PY'\n" + code + "\nPY",
                           "", [], start))
    return sorted(out, key=lambda c: c.line)


def python_blocks(text):
    """(first line number, code) of each ```python fence."""
    out = []
    lines = text.split("\n")
    k = 0
    while k < len(lines):
        if lines[k].strip() == "```python":
            end = next(e for e in range(k + 1, len(lines)) if lines[e].strip().startswith("```"))
            out.append((k + 2, "\n".join(lines[k + 1:end])))
            k = end
        k += 1
    return out


def all_commands():
    return [c for p in pages() for c in commands_of(p)]


# ---- comparing figures ------------------------------------------------------

def tokens(line):
    """(text between numbers, [(number, text before, text after)])."""
    numbers = []
    shape = []
    last = 0
    for m in NUMBER.finditer(line):
        # a number inside a word (out/door480.h5, f9026b5, x86-64) is text
        if (m.start() > 0 and (line[m.start() - 1].isalnum() or line[m.start() - 1] in "_/")) or \
           (m.end() < len(line) and (line[m.end()].isalpha() and line[m.end()] not in "eE") and
                line[m.end()] not in "sx"):
            continue
        shape.append(line[last:m.start()])
        numbers.append((m.group(0), line[max(0, m.start() - 12):m.start()], line[m.end():m.end() + 16]))
        last = m.end()
    shape.append(line[last:])
    return "\0".join(shape), numbers


def measured(before, after):
    return MEASURED_BEFORE.search(before) is not None or MEASURED_AFTER.search(after) is not None


class Findings:
    def __init__(self):
        self.fail = []
        self.warn = []

    def ratio(self, where, what, doc, now, seconds):
        try:
            d, n = float(doc), float(now)
        except ValueError:
            self.fail.append(f"{where}: {what}: {doc!r} in the doc, {now!r} now")
            return
        if seconds and max(d, n) < 0.5:
            return
        if d <= 0 or n <= 0:
            if d != n:
                self.warn.append(f"{where}: {what}: {doc} in the doc, {now} now")
            return
        r = max(d / n, n / d)
        message = f"{where}: {what}: {doc} in the doc, {now} now ({r:.1f}x)"
        if r > FAIL_RATIO:
            self.fail.append(message)
        elif r > WARN_RATIO:
            self.warn.append(message)


def compare_session(cmd, output, findings):
    """The lines shown under a `$ ` command against what it printed."""
    printed = output.split("\n")
    at = 0
    for shown in cmd.expected:
        shape, numbers = tokens(shown.strip())
        match = None
        for k in range(at, len(printed)):
            s, n = tokens(printed[k].strip())
            if s == shape and len(n) == len(numbers):
                match = (k, n)
                break
        if match is None:
            findings.fail.append(f"{cmd.where()}: `{cmd.text[:60]}` no longer prints\n"
                                 f"      {shown.strip()}\n    it prints\n      " +
                                 "\n      ".join(l for l in printed if l.strip()))
            continue
        at = match[0] + 1
        for (doc, before, after), (now, _, _) in zip(numbers, match[1]):
            what = f"{before.strip()} _ {after.strip()}".strip()
            if measured(before, after):
                findings.ratio(cmd.where(), f"`{what}`", doc, now, SECONDS_AFTER.search(after))
            elif doc != now:
                findings.fail.append(f"{cmd.where()}: `{cmd.text[:60]}` prints\n      "
                                     f"{printed[match[0]].strip()}\n    the doc shows\n      "
                                     f"{shown.strip()}\n    ({doc} against {now})")


def compare_comment(cmd, output, elapsed, findings):
    """`N snapshots` ... and `about N s` in a command's comment."""
    for number, word in COMMENT_COUNT.findall(cmd.comment):
        if not re.search(r"(?<![\w.])" + number + " " + word + r"\b", output):
            found = re.findall(r"(\d+) " + word + r"\b", output)
            findings.fail.append(f"{cmd.where()}: `# ... {number} {word}`: the command prints "
                                 f"{', '.join(f'{f} {word}' for f in found) or f'no {word}'}")
    for number, unit in COMMENT_TIME.findall(cmd.comment):
        doc = float(number) * (60 if unit == "min" else 1)
        findings.ratio(cmd.where(), "wall time in the comment (s)", f"{doc:g}", f"{elapsed:.2g}", True)


# ---- the scratch copy -------------------------------------------------------

def checkout_files():
    """The files of a fresh clone: git's, as they are in the working tree."""
    try:
        out = subprocess.run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
                             cwd=ROOT, capture_output=True, check=True).stdout
        return [p for p in out.decode().split("\0") if p and os.path.isfile(os.path.join(ROOT, p))]
    except (OSError, subprocess.CalledProcessError):
        skip_top = {"out", ".git", ".pytest_cache"}
        files = []
        for base, dirs, names in os.walk(ROOT):
            rel = os.path.relpath(base, ROOT)
            dirs[:] = [d for d in dirs if not (rel == "." and (d in skip_top or d.startswith("build")))
                       and d != "__pycache__"]
            files += [os.path.normpath(os.path.join(rel, n)) for n in names]
        return files


def make_scratch(dest):
    for rel in checkout_files():
        target = os.path.join(dest, rel)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        shutil.copy2(os.path.join(ROOT, rel), target, follow_symlinks=False)
    # the build as `make` leaves it, times kept (make finds it up to date):
    # not what `make test` adds (build/tests/, the fuzz replays)
    build = os.path.dirname(SANDSLIDE)
    os.makedirs(os.path.join(dest, "build"))
    for name in os.listdir(build):
        src, dst = os.path.join(build, name), os.path.join(dest, "build", name)
        if name in ("obj", "gen"):
            shutil.copytree(src, dst, symlinks=True)
        elif name in MADE_BY_MAKE or name.startswith("libsandslide."):
            shutil.copy2(src, dst, follow_symlinks=False)


def environment(scratch):
    env = dict(os.environ)
    for name in ("SANDSLIDE", "SANDSLIDE_NAN", "SANDSLIDE_PAUSE", "SANDSLIDE_LIBRARY", "PYTHONPATH",
                 "MAKEFLAGS", "MFLAGS", "MAKELEVEL"):
        env.pop(name, None)
    env["PATH"] = os.pathsep.join([os.path.join(scratch, "build"), os.path.dirname(sys.executable),
                                   env.get("PATH", "")])
    # the build's flags (`make test` passes them): the copy's `make` then
    # finds its build/ up to date, whatever built it
    flags = [w for w in os.environ.get("SANDSLIDE_MAKEFLAGS", "").split() if not w.startswith("BUILD=")]
    env["MAKEFLAGS"] = " ".join(["BUILD=build"] + flags)
    env.update(SANDSLIDE_CPU="generic", OMP_NUM_THREADS="2", OMP_WAIT_POLICY="passive",
               HOME=os.path.join(scratch, ".home"), LC_ALL="C.UTF-8",
               # a pytest the pages run keeps its files in the copy
               PYTEST_ADDOPTS="--basetemp=" + os.path.join(scratch, ".pytest-tmp"))
    os.makedirs(env["HOME"], exist_ok=True)
    return env


@functools.lru_cache(maxsize=None)
def importable(module):
    r = subprocess.run([sys.executable, "-c", f"import {module}"], capture_output=True)
    return r.returncode == 0


@functools.lru_cache(maxsize=None)
def build_has(feature):
    r = subprocess.run([SANDSLIDE, "--version"], capture_output=True, text=True)
    return f"{feature}: on" in r.stdout


# ---- the tests --------------------------------------------------------------

def test_commands_are_found():
    """The convention finds the commands the pages show (a change to it
    that finds none would pass everything)."""
    cmds = all_commands()
    where = {c.page for c in cmds}
    assert {"README.md", "doc/dem.md", "doc/rendering.md", "doc/bmi.md",
            "tests/README.md"} <= where, sorted(where)
    texts = [c.text for c in cmds]
    assert "sandslide run cases/dem.ini" in texts
    assert any(c.expected for c in cmds), "no `$ ` command shows its output"
    # synopses are not commands
    assert not any(t.startswith("sandslide relax DEM") for t in texts)


def test_synopsis_and_parts():
    assert is_synopsis("sandslide relax DEM [-o OUT]")
    assert is_synopsis("sandslide run x --set time.integrator=euler|rkl2")
    assert not is_synopsis("sandslide run cases/door.ini && sandslide render out/door.h5")
    assert not is_synopsis("cc prog.c $(pkg-config --cflags sandslide)")
    c = Command("x", 1, "make deps && make demo", "", [])
    assert c.run == "make demo" and c.skipped
    assert strip_comment("sandslide run a.ini   # -> out/a.h5 (3 snapshots)") == \
        ("sandslide run a.ini", "-> out/a.h5 (3 snapshots)")
    shape, numbers = tokens("wall 1.2 s: 39843 stencil evaluations, 5.9e+07 cell-updates/s on 2 threads")
    assert [n for n, _, _ in numbers] == ["1.2", "39843", "5.9e+07", "2"]
    assert [measured(b, a) for _, b, a in numbers] == [True, False, True, False]


def test_figures_are_compared():
    """What a `$ ` block and a comment hold against what a command prints:
    counts exact, measurements within 3x (else a warning; 30x fails)."""
    printed = ("wrote out/a.h5: 3 snapshots to t = 20 s, 14 super-steps (rkl2)\n"
               "wall 1.5 s: slope 0.1 s, sweep 1.3 s; 140 stencil evaluations, "
               "5e+07 cell-updates/s on 2 threads; 53 B per cell, peak 40.9 MiB\n")
    shown = ["wrote out/a.h5: 3 snapshots to t = 20 s, 14 super-steps (rkl2)",
             "wall 1.2 s: slope 0.3 s, sweep 1.0 s; 140 stencil evaluations, "
             "6e+07 cell-updates/s on 2 threads; 53 B per cell, peak 41.3 MiB"]

    def findings(expected, comment="", elapsed=1.5):
        f = Findings()
        cmd = Command("a page", 1, "sandslide run a.ini", comment, expected)
        compare_session(cmd, printed, f)
        compare_comment(cmd, printed, elapsed, f)
        return f

    f = findings(shown)
    assert not f.fail and not f.warn, (f.fail, f.warn)
    f = findings([shown[0].replace("14 super", "15 super")])
    assert len(f.fail) == 1 and "(15 against 14)" in f.fail[0], f.fail
    f = findings([shown[0].replace("t = 20 s", "t = 25 s")])
    assert len(f.fail) == 1, "a simulated time is exact"
    f = findings([shown[1].replace("140 stencil", "139 stencil")])
    assert len(f.fail) == 1
    f = findings(["wrote out/a.h5: 3 snapshots to t = 20 s (steady)"])
    assert len(f.fail) == 1 and "no longer prints" in f.fail[0], "another text fails"
    f = findings([shown[1].replace("wall 1.2 s", "wall 6 s")])
    assert not f.fail and len(f.warn) == 1 and "wall" in f.warn[0], (f.fail, f.warn)
    f = findings([shown[1].replace("wall 1.2 s", "wall 60 s")])
    assert len(f.fail) == 1, "a time 40 times off fails"
    f = findings([shown[1].replace("slope 0.3 s", "slope 0.01 s")])
    assert not f.fail and not f.warn, "times under 0.5 s are not compared"
    f = findings([shown[1].replace("5e+07", "5e+06").replace("6e+07", "6e+06")])
    assert len(f.warn) == 1, "a rate 10x off is flagged"
    f = findings([], comment="-> out/a.h5: 3 snapshots in about 2 s")
    assert not f.fail and not f.warn, (f.fail, f.warn)
    f = findings([], comment="-> out/a.h5: 4 snapshots", elapsed=9.0)
    assert len(f.fail) == 1 and "prints 3 snapshots" in f.fail[0], f.fail
    f = findings([], comment="in about 2 s", elapsed=9.0)
    assert len(f.warn) == 1 and not f.fail, (f.fail, f.warn)


def run_commands(commands, scratch, title):
    """Run commands in order in scratch; fail with every command that
    failed and every figure that is not what its command prints."""
    env = environment(scratch)
    unchecked = set()     # blocks after a shortened or left-out command
    findings = Findings()
    log = []
    failed = []
    started = time.monotonic()
    for cmd in commands:
        for part, why in cmd.skipped:
            log.append(f"  skip  {cmd.where()}: {part}\n        ({why})")
        if not cmd.run:
            continue
        missing = next((what for pat, what, have in REQUIRES
                        if re.search(pat, cmd.run) and not have()), None)
        program = first_word(cmd.run)
        if not missing and program.startswith("/") and not os.access(program, os.X_OK):
            missing = f"{program}, not installed"
        if missing:
            log.append(f"  skip  {cmd.where()}: {cmd.run}\n        (needs {missing})")
            unchecked.add(cmd.block)
            continue
        t0 = time.monotonic()
        try:
            r = subprocess.run(["bash", "-c", "set -o pipefail; " + cmd.run], cwd=scratch, env=env,
                               capture_output=True, text=True, timeout=600, stdin=subprocess.DEVNULL)
        except subprocess.TimeoutExpired:
            pytest.fail(f"{cmd.where()}: `{cmd.run}` ran for 600 s")
        elapsed = time.monotonic() - t0
        note = f"  (shortened: {cmd.shortened})" if cmd.shortened else ""
        log.append(f"  {elapsed:5.1f}s {cmd.where()}: {cmd.run.split(chr(10))[0]}{note}")
        if r.returncode != 0:
            # go on: the failures after it may or may not follow from it
            failed.append(f"{cmd.where()}: `{cmd.run}` exited {r.returncode}:\n"
                          f"    stdout: {r.stdout[-1500:].strip()}\n    stderr: {r.stderr[-1500:].strip()}")
            log[-1] += "   FAILED"
            unchecked.add(cmd.block)
            continue
        if cmd.shortened:
            unchecked.add(cmd.block)
        if cmd.block in unchecked:
            continue
        output = r.stdout + r.stderr
        compare_session(cmd, output, findings)
        compare_comment(cmd, output, elapsed, findings)
    print(f"{title} ({time.monotonic() - started:.0f} s):\n" + "\n".join(log))
    for w in findings.warn:
        warnings.warn(f"a measurement in the docs is more than {WARN_RATIO:g}x off: {w}")
    problems = []
    if failed:
        problems.append(f"{len(failed)} commands fail in a fresh copy of the checkout after `make`, "
                        f"run in order:\n" + "\n".join(failed))
    if findings.fail:
        problems.append(f"{len(findings.fail)} figures are not what their commands print:\n  " +
                        "\n  ".join(findings.fail))
    assert not problems, "\n\n".join(problems) + f"\n\n{title}:\n" + "\n".join(log)


def need_build():
    if not os.path.isfile(os.path.join(os.path.dirname(SANDSLIDE), "libsandslide.so.0")):
        pytest.skip("no libsandslide.so.0 beside SANDSLIDE: run `make`")


def test_doc_commands_run_in_order_and_print_their_figures(tmp_path):
    """Every command of the pages, in order, in a fresh copy of the
    checkout after `make`: exit 0, and the figures shown beside it."""
    need_build()
    scratch = str(tmp_path / "clone")
    make_scratch(scratch)
    run_commands(all_commands(), scratch, "the docs' commands")


def case_headers():
    """A Command for each shipped case's header: its `command:` line, with
    its `runtime:` lines as the comment."""
    out = []
    for path in sorted(glob.glob(os.path.join(ROOT, "cases", "*.ini"))):
        head = []
        with open(path) as f:
            for line in f:
                if not line.startswith("#"):
                    break
                head.append(line[1:].strip())
        text = " ".join(head)
        m = re.search(r"\bcommand:\s+(.*?)(?:\s+\(|\s+runtime:|$)", text)
        r = re.search(r"\bruntime:\s+(.*?)(?:\s+writes:|$)", text)
        if not m:
            continue
        name = "cases/" + os.path.basename(path)
        line = next(k for k, l in enumerate(head, 1) if l.startswith("command:"))
        out.append(Command(name, line, m.group(1).strip(), r.group(1) if r else "", [], "header"))
    return out


def test_case_headers_run_and_print_their_figures(tmp_path):
    """Each shipped case's header gives the command that runs it and what
    that takes: the command runs in a fresh copy of the checkout, and the
    counts and the time (`about N s`) of its `runtime:` are what it prints
    and takes."""
    need_build()
    headers = case_headers()
    assert {"cases/door.ini", "cases/dem.ini"} <= {c.page for c in headers}, \
        [c.page for c in headers]
    for c in headers:
        assert c.run, f"{c.where()}: no command: {c.text!r}"
    scratch = str(tmp_path / "clone")
    make_scratch(scratch)
    run_commands(headers, scratch, "the case files' commands")


if __name__ == "__main__":
    # python3 tests/cli/test_doc_commands.py: list what the test would run
    for c in all_commands():
        for part, why in c.skipped:
            print(f"{c.where()}: skip {part!r}: {why}")
        if c.run:
            print(f"{c.where()}: {c.run}" + (f"   [shortened: {c.shortened}]" if c.shortened else "")
                  + (f"   # {c.comment}" if c.comment else "")
                  + (f"   ({len(c.expected)} lines shown)" if c.expected else ""))
