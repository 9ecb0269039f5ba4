"""doc/sandslide.1 in step with `sandslide --help`.

The man page is written by hand (man(7) roff), the help is generated from
the option tables of src/cli/main.c: these tests hold the two together.
Every option of `sandslide CMD --help` (each -x/--long name with the value
it names, "--angle DEG") must be a .TP entry of the subsection `.SS CMD`
under COMMANDS with the same value name, and the page may document no
option the command's help lacks; the options of `sandslide --help` itself
(--help, --version) are the .TP entries of the page's OPTIONS section.
Every command of `sandslide --help` has its subsection and its SYNOPSIS
line, and the page names no other.  groff renders the page without a
warning.

A tag is compared as the text it renders to, fonts and escapes removed
("\\fB\\-o\\fR, \\fB\\-\\-output \\fIOUT.h5\\fR" is "-o, --output OUT.h5"), so
the page may use any of the font macros for it.
"""
import os
import re
import shutil
import subprocess

import pytest

from conftest import run_ok

HERE = os.path.dirname(os.path.abspath(__file__))
MANPAGE = os.path.normpath(os.path.join(HERE, "..", "..", "doc", "sandslide.1"))

# The help's second column (HELP_COLUMN of src/cli/options.c): an option's
# text starts there, so a word after the option's name that starts before
# it is the name of its value.
HELP_COLUMN = 24

NAME = r"--?[A-Za-z0-9][A-Za-z0-9-]*"
# "-o, --output OUT.h5", "--force", "--bench [N]": names, then the value
ENTRY = re.compile(rf"((?:{NAME}, )*{NAME})(?: (\S+))?")
ALTERNATING = {"BR", "BI", "IB", "IR", "RB", "RI"}
FONT_MACROS = {"B", "I", "SM", "SB"} | ALTERNATING


# ---- sandslide --help -----------------------------------------------------

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


def help_top_options(text):
    """Every -x/--long word of `sandslide --help`, as help_options gives
    them (it names no values)."""
    return {n: ((n,), None) for n in re.findall(rf"(?<![\w-])({NAME})", text)}


def help_options(text, command):
    """The option entries of `sandslide CMD --help`: {name: (names, value)},
    the value None for a flag."""
    options = {}
    for line in text.splitlines():
        if not line.startswith("  -"):
            continue
        m = ENTRY.match(line, 2)
        assert m, f"{command}: cannot read the option line {line!r} of its --help"
        names = tuple(m.group(1).split(", "))
        value = m.group(2)
        # a flag's text starts at the second column; a value before it, or
        # on a line of its own (the option too long for the column)
        if value is not None and not (m.start(2) < HELP_COLUMN or
                                      m.end(2) == len(line.rstrip())):
            value = None
        for n in names:
            assert n not in options, f"{command}: --help lists {n} twice"
            options[n] = (names, value)
    return options


# ---- doc/sandslide.1 ------------------------------------------------------

def roff_words(args):
    """A macro line's arguments: split at unescaped blanks, "quoted" kept
    together ("" inside quotes is a quote)."""
    words, k = [], 0
    while k < len(args):
        if args[k] in " \t":
            k += 1
            continue
        quoted = args[k] == '"'
        k += quoted
        word = []
        while k < len(args):
            if quoted and args[k] == '"':
                if args[k + 1:k + 2] != '"':
                    k += 1
                    break
                word.append('"')
                k += 2
            elif not quoted and args[k] in " \t":
                break
            elif args[k] == "\\" and k + 1 < len(args):
                word.append(args[k:k + 2])   # an escape stays whole
                k += 2
            else:
                word.append(args[k])
                k += 1
        words.append("".join(word))
    return words


ESCAPES = [
    (re.compile(r"\\f(?:\[[^\]]*\]|\(..|.)"), ""),   # font changes
    (re.compile(r"\\\(aq"), "'"),
    (re.compile(r"\\\((?:lq|rq)"), '"'),
    (re.compile(r"\\\((?:em|en|hy|mi)"), "-"),
    (re.compile(r"\\\(ha"), "^"),
    (re.compile(r"\\\(ti"), "~"),
    (re.compile(r"\\\(..|\\\[[^\]]*\]"), "?"),        # any other glyph
    (re.compile(r"\\[&%]"), ""),
    (re.compile(r"\\[ ~0]"), " "),
    (re.compile(r"\\-"), "-"),
    (re.compile(r"\\e"), "\\\\"),
]


def roff_plain(text):
    """The text a piece of roff renders to, without fonts."""
    for pattern, replacement in ESCAPES:
        text = pattern.sub(replacement, text)
    return text


def line_text(line):
    """The plain text of a source line: text as it is, the arguments of a
    font macro (.B, .BR, ...) joined as it joins them; None for any other
    request."""
    if not line.startswith((".", "'")):
        return roff_plain(line)
    name, _, args = line[1:].strip().partition(" ")
    if name not in FONT_MACROS:
        return None
    words = roff_words(args)
    return roff_plain(("" if name in ALTERNATING else " ").join(words))


def man_lines():
    with open(MANPAGE, encoding="utf-8") as f:
        raw = f.read().splitlines()
    lines = []
    for line in raw:
        if line.startswith(('.\\"', "'\\\"", '.\\#')) or line == ".":
            continue
        if lines and lines[-1].endswith("\\") and not lines[-1].endswith("\\\\"):
            lines[-1] = lines[-1][:-1] + line     # a continued line
        else:
            lines.append(line)
    return lines


def man_sections():
    """{SECTION: [source lines]} of the page, and {command: [source lines]}
    of the subsections of COMMANDS."""
    sections, subsections = {}, {}
    section = subsection = None
    for line in man_lines():
        if re.match(r"\.SH\b", line):
            section = roff_plain(" ".join(roff_words(line[3:])))
            assert section not in sections, f"the man page has two sections {section}"
            sections[section] = []
            subsection = None
            continue
        if re.match(r"\.SS\b", line) and section == "COMMANDS":
            title = roff_plain(" ".join(roff_words(line[3:])))
            subsection = title.split()[0] if title.split() else ""
            assert subsection not in subsections, \
                f"the man page's COMMANDS has two subsections .SS {subsection}"
            subsections[subsection] = []
            continue
        if section is not None:
            sections[section].append(line)
        if subsection is not None:
            subsections[subsection].append(line)
    return sections, subsections


def man_options(lines, where):
    """The options of the .TP entries in lines: {name: [(names, value)]},
    a list so that an option documented twice shows.  Tags that are not
    options (arguments such as CASE.ini) are left out."""
    options = {}
    for k, line in enumerate(lines):
        if not re.match(r"\.TP\b", line):
            continue
        tag = next((line_text(t) for t in lines[k + 1:] if line_text(t) is not None), None)
        if tag is None or not tag.strip().startswith("-"):
            continue
        tag = " ".join(tag.split())
        m = ENTRY.fullmatch(tag)
        assert m, (f"{where}: the man page's tag {tag!r} is not an option and the "
                   f"name of its value, as in '--angle DEG' or '-o, --output OUT.h5'")
        names = tuple(m.group(1).split(", "))
        for n in names:
            options.setdefault(n, []).append((names, m.group(2)))
    return options


def synopsis_commands(lines):
    """The command of each SYNOPSIS line ("sandslide run ..." -> run); the
    lines of the global options (sandslide --version) name none."""
    entries, current = [], []
    for line in lines + [".br"]:
        text = line_text(line)
        if text is None:
            if re.match(r"\.(br|PP|LP|P|sp)\b", line) and current:
                entries.append(" ".join(current).split())
                current = []
            continue
        current.append(text)
    commands = []
    for words in entries:
        assert words[0] == "sandslide", \
            f"the SYNOPSIS line {' '.join(words)!r} does not start with 'sandslide'"
        if len(words) > 1 and re.fullmatch(r"[a-z][a-z0-9-]*", words[1]):
            commands.append(words[1])
    return commands


# ---- what is compared -----------------------------------------------------

def compare(command, helped, documented, page_part):
    """The differences between the options of a command's --help and the
    page's entries, one message each."""
    problems = []
    cmd = f"sandslide {command}".rstrip()
    for name, (names, value) in helped.items():
        entries = documented.get(name)
        if not entries:
            problems.append(f"{cmd}: {name} is in `{cmd} --help` but missing from the man "
                            f"page's {page_part}")
            continue
        if len(entries) > 1:
            problems.append(f"{cmd}: {name} is documented {len(entries)} times in the man "
                            f"page's {page_part}")
        man_names, man_value = entries[0]
        if man_value != value:
            problems.append(f"{cmd}: {name} takes {value or 'no value'} in `{cmd} --help` "
                            f"but {man_value or 'no value'} in the man page's {page_part}")
        if man_names != names:
            problems.append(f"{cmd}: --help gives {', '.join(names)} as one option, the man "
                            f"page's {page_part} {', '.join(man_names)}")
    for name in documented:
        if name not in helped:
            problems.append(f"{cmd}: {name} is documented in the man page's {page_part} but "
                            f"missing from `{cmd} --help` (the command has no such option)")
    return problems


MAIN_HELP = help_text()
COMMANDS = help_commands(MAIN_HELP)


@pytest.fixture(scope="module")
def page():
    assert os.path.isfile(MANPAGE), f"no man page at {MANPAGE}"
    return man_sections()


def test_page_has_its_sections(page):
    sections, _ = page
    for name in ("NAME", "SYNOPSIS", "DESCRIPTION", "COMMANDS", "EXIT STATUS", "SEE ALSO"):
        assert name in sections, f"the man page has no section {name}"


@pytest.mark.parametrize("command", COMMANDS)
def test_command_options_documented(page, command):
    _, subsections = page
    if command not in subsections:
        pytest.fail(f"sandslide {command}: in `sandslide --help` but the man page has no "
                    f"`.SS {command}` under COMMANDS", pytrace=False)
    helped = help_options(help_text(command), command)
    documented = man_options(subsections[command], f"sandslide {command}")
    problems = compare(command, helped, documented, f"`.SS {command}`")
    assert not problems, "\n".join(problems)


def help_defaults(text):
    """{option name: its default} of `sandslide CMD --help`, where the help
    gives one: "(default X)" at the end of its text, which the help adds
    from the library's option tables (include/sandslide/option.h)."""
    defaults, current, body = {}, None, []
    for line in text.splitlines() + ["  --end-of-help"]:
        if line.startswith("  -") or not line.startswith(" "):
            if current:
                m = re.search(r"\(default ([^\s();]+)\)$", " ".join(" ".join(body).split()))
                if m:
                    defaults[current] = m.group(1)
            current, body = None, []
            m = ENTRY.match(line, 2) if line.startswith("  -") else None
            if m:
                current = m.group(1).split(", ")[-1]
        body.append(line)
    return defaults


def man_entry_texts(lines):
    """{option name: the plain text of its .TP entry} of lines."""
    texts, current = {}, None
    for k, line in enumerate(lines):
        if re.match(r"\.(TP|SS|SH|PP|LP|P)\b", line):
            current = None
            if re.match(r"\.TP\b", line):
                tag = next((line_text(t) for t in lines[k + 1:] if line_text(t) is not None),
                           None)
                m = ENTRY.fullmatch(" ".join(tag.split())) if tag and tag.strip().startswith(
                    "-") else None
                if m:
                    current = m.group(1).split(", ")[-1]
                    texts[current] = []
            continue
        if current:
            text = line_text(line)
            if text is not None:
                texts[current].append(text)
    return {n: " ".join(" ".join(t).split()) for n, t in texts.items()}


@pytest.mark.parametrize("command", COMMANDS)
def test_defaults_documented(page, command):
    """Each default `sandslide CMD --help` gives (from the option tables)
    is the one the man page's entry states."""
    _, subsections = page
    if command not in subsections:
        pytest.fail(f"the man page has no `.SS {command}`", pytrace=False)
    texts = man_entry_texts(subsections[command])
    problems = []
    for name, default in help_defaults(help_text(command)).items():
        text = texts.get(name, "")
        if not re.search(rf"(?<![\w.-]){re.escape(default)}(?![\w-])(?!\.\d)", text):
            problems.append(f"sandslide {command} {name}: --help gives the default {default}, "
                            f"but the man page's entry does not say it: {text[:200]!r}")
    assert not problems, "\n".join(problems)


def test_global_options_documented(page):
    sections, _ = page
    assert "OPTIONS" in sections, \
        "the man page has no OPTIONS section for the options of `sandslide --help`"
    problems = compare("", help_top_options(MAIN_HELP),
                       man_options(sections["OPTIONS"], "sandslide"), "OPTIONS section")
    assert not problems, "\n".join(problems)


def test_commands_match(page):
    sections, subsections = page
    synopsis = synopsis_commands(sections["SYNOPSIS"])
    problems = []
    for c in COMMANDS:
        if c not in subsections:
            problems.append(f"sandslide {c}: in `sandslide --help` but the man page has no "
                            f"`.SS {c}` under COMMANDS")
        if c not in synopsis:
            problems.append(f"sandslide {c}: in `sandslide --help` but missing from the man "
                            f"page's SYNOPSIS")
    for c in subsections:
        if c not in COMMANDS:
            problems.append(f"sandslide {c}: the man page has `.SS {c}` under COMMANDS but "
                            f"`sandslide --help` has no such command")
    for c in synopsis:
        if c not in COMMANDS:
            problems.append(f"sandslide {c}: in the man page's SYNOPSIS but `sandslide --help` "
                            f"has no such command")
    for c in set(synopsis):
        if synopsis.count(c) > 1:
            problems.append(f"sandslide {c}: {synopsis.count(c)} lines in the man page's "
                            f"SYNOPSIS (expected one per command)")
    assert not problems, "\n".join(problems)


def test_groff_renders_without_warnings():
    groff = shutil.which("groff")
    if groff is None:
        pytest.skip("groff is not installed (Debian package groff-base): cannot check that "
                    "the man page renders without warnings")
    r = subprocess.run([groff, "-man", "-Tutf8", "-ww", "-z", MANPAGE],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and r.stderr == "", (
        f"groff -man -Tutf8 -ww -z {MANPAGE} exited {r.returncode} with:\n{r.stderr}")
