# SPDX-License-Identifier: BSD-3-Clause
"""The man page `make` builds beside sandslide ($(BUILD)/sandslide.1).

doc/sandslide.1.in is written by hand but for each command's options,
which doc/manpage.awk fills in from `sandslide help --roff CMD`: the option
tables' text and defaults, as --help shows them.  What that makes true by
construction is checked cheaply; what is written by hand is checked where
it names commands and options:

- the page is the template filled in by this sandslide (make has run since
  either changed), and no directive of the template is left in it;
- groff renders it without a warning;
- every command of `sandslide --help` has its SYNOPSIS line, its `.SS` under
  COMMANDS and one @options block in the template, and no other command;
- every option of `sandslide CMD --help` is one .TP entry of `.SS CMD`, and
  no other option is; the OPTIONS section has those of `sandslide --help`;
- every option an example gives is one of its command's;
- doc/manpage.awk puts a note after its option's entry, and makes no page
  from a note for an option the command lacks, a block not closed or a
  program that fails.
"""
import os
import re
import shutil
import subprocess

import pytest

from conftest import ROOT, SANDSLIDE, run_ok

PAGE = os.path.join(os.path.dirname(SANDSLIDE), "sandslide.1")
TEMPLATE = os.path.join(ROOT, "doc", "sandslide.1.in")
AWK = os.path.join(ROOT, "doc", "manpage.awk")
DIRECTIVE = re.compile(r'^\.\\" @(\w+)(?: (\S+))?', re.M)
OPTION = re.compile(r"--?[A-Za-z][A-Za-z0-9-]*")
FONT_MACROS = {"B", "I", "BR", "BI", "IB", "IR", "RB", "RI"}


def help_text(*command):
    r = run_ok(list(command) + ["--help"])
    assert r.stderr == "", f"sandslide {' '.join(command)} --help wrote to stderr:\n{r.stderr}"
    return r.stdout


def help_commands(text):
    """The commands listed under "commands:" in `sandslide --help`."""
    lines = text.splitlines()
    assert "commands:" in lines, "sandslide --help has no 'commands:' list"
    names = []
    for line in lines[lines.index("commands:") + 1:]:
        if not line.strip():
            break
        names.append(line.split()[0])
    assert names, "sandslide --help lists no command"
    return names


def help_options(text):
    """The names of the options of a command's --help ("-o", "--output"):
    the words before the value on each line that starts with "  -"."""
    names = []
    for line in text.splitlines():
        if line.startswith("  -"):
            left = re.split(r"\s{2,}", line.strip())[0]
            names += [w.rstrip(",") for w in left.split() if OPTION.fullmatch(w.rstrip(","))]
    return names


MAIN_HELP = help_text()
COMMANDS = help_commands(MAIN_HELP)


def fill(template, program=SANDSLIDE):
    return subprocess.run(["awk", "-v", f"program={program}", "-f", AWK, str(template)],
                          capture_output=True, text=True, timeout=120)


# ---- the page, as source lines ---------------------------------------------

def plain(text):
    """The text a piece of roff renders to, without fonts."""
    text = re.sub(r"\\f(?:\[[^\]]*\]|\(..|.)", "", text)
    for escape, char in (("\\(aq", "'"), ("\\-", "-"), ("\\&", ""), ("\\e", "\\")):
        text = text.replace(escape, char)
    return text


def line_text(line):
    """A source line's text: text as it is, a font macro's arguments joined;
    None for any other request or a comment."""
    if not line.startswith((".", "'")):
        return plain(line)
    name, _, args = line[1:].partition(" ")
    if name not in FONT_MACROS:
        return None
    return plain(args.replace('"', "").replace(" ", "" if len(name) == 2 else " "))


@pytest.fixture(scope="module")
def page():
    if not os.path.isfile(PAGE):
        pytest.fail(f"no man page at {PAGE}: run make", pytrace=False)
    with open(PAGE, encoding="utf-8") as f:
        return f.read()


@pytest.fixture(scope="module")
def sections(page):
    """{SECTION: [source lines]}, and for COMMANDS' subsections
    {"COMMANDS run": [...]}."""
    out, current = {}, []
    for line in page.splitlines():
        m = re.match(r"\.(SH|SS) (.*)", line)
        if m:
            title = m.group(2).strip('"')
            key = title if m.group(1) == "SH" else f"COMMANDS {title.split()[0]}"
            assert key not in out, f"the man page has two sections {key}"
            current = out[key] = []
        current.append(line)
    return out


def tags(lines):
    """The option names of the .TP entries in lines, each as often as it is
    documented; tags that are not options (CASE.ini) left out."""
    names = []
    for k, line in enumerate(lines[:-1]):
        if line == ".TP":
            tag = line_text(lines[k + 1]) or ""
            if tag.startswith("-"):
                names += [w.rstrip(",") for w in tag.split() if OPTION.fullmatch(w.rstrip(","))]
    return names


# ---- what is checked --------------------------------------------------------

def test_page_is_the_template_filled(page):
    r = fill(TEMPLATE)
    assert r.returncode == 0 and r.stderr == "", f"doc/manpage.awk failed:\n{r.stderr}"
    assert page == r.stdout, (f"{PAGE} is not doc/sandslide.1.in filled in by {SANDSLIDE}: "
                              f"run make")
    left = [m.group(0) for m in DIRECTIVE.finditer(page)]
    assert not left, f"directives of the template left in the page: {left}"


def test_groff_renders_without_warnings(page):
    groff = shutil.which("groff")
    if groff is None:
        pytest.skip("groff is not installed (Debian package groff-base): cannot check that "
                    "the man page renders without warnings")
    r = subprocess.run([groff, "-man", "-Tutf8", "-ww", "-z", PAGE],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and r.stderr == "", (
        f"groff -man -Tutf8 -ww -z {PAGE} exited {r.returncode} with:\n{r.stderr}")


def test_commands_match(sections):
    with open(TEMPLATE, encoding="utf-8") as f:
        blocks = [m.group(2) for m in DIRECTIVE.finditer(f.read()) if m.group(1) == "options"]
    synopsis = [m.group(1) for line in sections["SYNOPSIS"]
                for m in [re.match(r"\.B sandslide ([a-z][a-z0-9-]*)", line)] if m]
    subsections = [k.split()[1] for k in sections if k.startswith("COMMANDS ")]
    for name in ("NAME", "DESCRIPTION", "OPTIONS", "EXIT STATUS", "ENVIRONMENT", "FILES",
                 "EXAMPLES", "SEE ALSO"):
        assert name in sections, f"the man page has no section {name}"
    for what, found in (("SYNOPSIS lines", synopsis), ("`.SS` under COMMANDS", subsections),
                        ("@options blocks of doc/sandslide.1.in", blocks)):
        assert sorted(found) == sorted(COMMANDS), (
            f"the commands of `sandslide --help` are {COMMANDS}, the {what} {found}")


@pytest.mark.parametrize("command", COMMANDS)
def test_command_options_documented(sections, command):
    helped = help_options(help_text(command))
    documented = tags(sections.get(f"COMMANDS {command}", []))
    assert sorted(documented) == sorted(helped), (
        f"sandslide {command}: the options of --help are {sorted(helped)}, the .TP entries of "
        f"the man page's `.SS {command}` {sorted(documented)}")


def test_global_options_documented(sections):
    helped = set(re.findall(r"(?<![\w-])(--?[A-Za-z][A-Za-z0-9-]*)", MAIN_HELP))
    documented = tags(sections["OPTIONS"])
    assert sorted(documented) == sorted(helped), (
        f"`sandslide --help` names {sorted(helped)}, the page's OPTIONS {documented}")


def test_examples_give_their_commands_options(sections):
    lines, shown = [], False
    for line in sections["EXAMPLES"]:
        shown = {".nf": True, ".fi": False}.get(line, shown)
        if shown and line_text(line) is not None:
            lines.append(line_text(line))
    text = re.sub(r"\\\n", " ", "\n".join(lines))
    options = {c: set(help_options(help_text(c))) for c in COMMANDS}
    seen = []
    for segment in re.split(r"&&|;|\n", text):
        words = segment.split()
        if not words or words[0] != "sandslide":
            continue
        assert len(words) > 1 and words[1] in COMMANDS, f"an example runs no command: {segment}"
        seen.append(words[1])
        for w in words[2:]:
            name = w.split("=")[0]
            if OPTION.fullmatch(name):
                assert name in options[words[1]], (
                    f"the example `{segment.strip()}` gives {name}, which `sandslide "
                    f"{words[1]} --help` does not list")
    assert seen, "the man page's EXAMPLES run no sandslide command"


# ---- doc/manpage.awk --------------------------------------------------------

def test_a_note_follows_its_option(tmp_path):
    template = tmp_path / "t.1.in"
    template.write_text('.\\" @options bench\n.\\" @note --nx\nNOTE ON NX\n.\\" @end\nEND\n')
    r = fill(template)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    at = lines.index("\\fB\\-\\-nx\\fR \\fIN\\fR")
    assert lines[at - 1] == ".TP" and lines[at + 2:at + 4] == [".IP", "NOTE ON NX"], lines
    assert lines[at + 4] == ".TP" and lines[-1] == "END", lines


@pytest.mark.parametrize("text, message", [
    ('.\\" @options bench\n.\\" @note --no-such\nx\n.\\" @end\n', "--no-such"),
    ('.\\" @options bench\n.\\" @note --nx\nx\n', "no @end"),
    ('.\\" @options nosuch\n.\\" @end\n', "failed"),
])
def test_a_template_that_cannot_be_filled_makes_no_page(tmp_path, text, message):
    template = tmp_path / "t.1.in"
    template.write_text(text)
    r = fill(template)
    assert r.returncode != 0 and message in r.stderr, (r.returncode, r.stderr)
