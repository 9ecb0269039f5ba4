# SPDX-License-Identifier: BSD-3-Clause
"""The documentation resolves inside the repository (doc/README.md).

- Every reference to a Markdown file in a comment (or string) of src/,
  render/, include/, tests/, python/, tools/, cases/ and the Makefile names
  a file of the repository, root-relative (`doc/model.md`), and with
  `#anchor` a heading of it (`doc/model.md#face-flux`).
- Nothing there, nor in the README or doc/, refers to the design document
  that lives outside the repository (its "section N") or to anything else
  outside it, nor to a README section by its name (they moved to doc/).
- Every relative link and image of README.md, doc/*.md and the folders'
  READMEs reaches a file of the repository, and with `#anchor` a heading.
- Every citation key, `[Paper]`, `[Horn]`, ..., used in those files is a
  heading of doc/references.md.
- README.md is a front page: under 300 lines.

Anchors follow GitHub's rule: the heading's text, lowercase, with every
character that is not a letter, digit, space, '-' or '_' dropped and spaces
turned into '-'; a repeated heading gets -1, -2, ...  Each failure names
file:line and what is missing.  Reads files only: no binary is needed.
"""
import difflib
import os
import re
import unicodedata
import urllib.parse

from conftest import ROOT

# Where code may cite the docs (the trees of doc/README.md's rule).
CODE_TREES = ["src", "render", "include", "tests", "python", "tools", "cases"]
CODE_FILES = ["Makefile"]
# Inputs of the fuzzers: data, not text to check.
SKIP_DIRS = {os.path.join("tests", "fuzz", "corpus"), os.path.join("tests", "fuzz", "regressions"),
             "__pycache__", ".pytest_cache"}
SELF = os.path.relpath(os.path.abspath(__file__), ROOT)

# The Markdown pages whose links must resolve.
PAGES = ["README.md", "tests/README.md", "src/README.md", "render/README.md",
         "tests/fuzz/README.md"]

# Built from parts so that this file does not match itself.
OLD_SPEC = re.compile(r"\b" + "SP" + r"EC\b")
OUTSIDE = re.compile(re.escape(".." + "/shared"))
README_SECTION = re.compile(r"README(?:\.md)?(?:'s)?,?\s+(?:section\s+)?\"?[A-Z][a-z]|"
                            r"README(?:'s)?\s+section|section of the README|\(README,?\s*$")
# A root-relative path of a Markdown file, with an optional anchor.
MD_PATH = re.compile(r"(?<![\w/.\-])((?:\.\./)*(?:[\w.\-]+/)*[\w\-]+\.md)(#[\w\-]*)?")
# Citation keys: [Paper], [Horn], [Meyer2014]; not x[None] (indexing) and
# not [text](link) or [text][ref].
KEY = re.compile(r"(?<![\w\]\)\[`])\[([A-Z][a-z]+(?:[A-Z][a-z]+)*(?:\d{4})?)\]"
                 r"(?![(\[:])")
# Bracketed words that are not citations: "[None]" quotes ParaView's
# message in src/io/sidecar.c.
NOT_KEYS = {"None"}
LINK_TARGET = re.compile(r"\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
LINK_DEF = re.compile(r"^\s{0,3}\[[^\]]+\]:\s*<?(\S+?)>?(?:\s+\"[^\"]*\")?\s*$")
HTML_REF = re.compile(r"<(?:img|a)\b[^>]*?\s(?:src|href)=\"([^\"]+)\"")
EXTERNAL = re.compile(r"^[A-Za-z][A-Za-z0-9+.\-]*:")


def rel(path):
    return os.path.relpath(path, ROOT)


def text_files():
    """Every text file of the code trees, root-relative, sorted."""
    out = list(CODE_FILES)
    for tree in CODE_TREES:
        for base, dirs, files in os.walk(os.path.join(ROOT, tree)):
            dirs[:] = sorted(d for d in dirs
                             if d not in SKIP_DIRS and rel(os.path.join(base, d)) not in SKIP_DIRS)
            for name in sorted(files):
                path = os.path.join(base, name)
                with open(path, "rb") as f:
                    data = f.read()
                if b"\0" not in data:
                    out.append(rel(path))
    return out


def read_lines(relpath):
    with open(os.path.join(ROOT, relpath), encoding="utf-8", errors="replace") as f:
        return f.read().split("\n")


def doc_pages():
    doc = os.path.join(ROOT, "doc")
    return PAGES + sorted("doc/" + n for n in os.listdir(doc) if n.endswith(".md"))


def prose_lines(lines):
    """(number, line) of the Markdown lines outside code: fenced blocks and
    indented blocks dropped, inline code spans blanked."""
    fence = None
    previous_blank = True
    in_indented = False
    for number, line in enumerate(lines, 1):
        stripped = line.lstrip()
        if fence:
            if stripped.startswith(fence):
                fence = None
            previous_blank = False
            continue
        if stripped.startswith("```") or stripped.startswith("~~~"):
            fence = stripped[:3]
            continue
        blank = not line.strip()
        indented = line.startswith("    ") or line.startswith("\t")
        if indented and (previous_blank or in_indented):
            in_indented = True
            previous_blank = False
            continue
        if not blank:
            in_indented = False
        previous_blank = blank
        yield number, re.sub(r"`[^`]*`", lambda m: " " * len(m.group(0)), line)


def slug(heading):
    """GitHub's anchor of a heading's text."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading)   # links: their text
    text = text.replace("`", "").replace("*", "")
    text = re.sub(r"<[^>]+>", "", text).strip().lower()
    kept = []
    for ch in text:
        cat = unicodedata.category(ch)
        if ch in " -_" or cat[0] in "LNM":
            kept.append(ch)
    return "".join(kept).replace(" ", "-")


_anchor_cache = {}


def anchors(relpath):
    """The anchors of the headings of a Markdown file (and of explicit
    <a id/name> tags)."""
    if relpath in _anchor_cache:
        return _anchor_cache[relpath]
    seen = {}
    out = set()
    lines = read_lines(relpath)
    fence = None
    for line in lines:
        stripped = line.lstrip()
        if fence:
            if stripped.startswith(fence):
                fence = None
            continue
        if stripped.startswith("```") or stripped.startswith("~~~"):
            fence = stripped[:3]
            continue
        m = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
        if m:
            base = slug(m.group(1))
            n = seen.get(base, 0)
            out.add(base if n == 0 else f"{base}-{n}")
            seen[base] = n + 1
        for a in re.findall(r"<a\s+(?:id|name)=\"([^\"]+)\"", line):
            out.add(a)
    _anchor_cache[relpath] = out
    return out


def check_target(where, relpath, anchor, problems):
    """relpath (root-relative, normalised) must be a file or folder of the
    repository; a Markdown file with an anchor must have that heading."""
    full = os.path.normpath(os.path.join(ROOT, relpath))
    if full != ROOT and not full.startswith(ROOT + os.sep):
        problems.append(f"{where}: {relpath} is outside the repository")
        return
    if not os.path.exists(full):
        problems.append(f"{where}: {rel(full)} does not exist")
        return
    if anchor and full.endswith(".md"):
        have = anchors(rel(full))
        if anchor not in have:
            near = difflib.get_close_matches(anchor, sorted(have), n=3, cutoff=0.0)
            problems.append(f"{where}: {rel(full)} has no heading #{anchor} "
                            f"(closest: {', '.join('#' + a for a in near)})")


def report(problems, what):
    assert not problems, f"{len(problems)} {what}:\n  " + "\n  ".join(problems)


def test_code_cites_existing_doc_sections():
    """`doc/model.md#face-flux` in a comment: the file and the heading
    exist (root-relative)."""
    problems = []
    for path in text_files():
        if path == SELF:
            continue
        markdown = path.endswith(".md")
        for number, line in enumerate(read_lines(path), 1):
            if markdown:   # links are checked file-relative below
                line = LINK_TARGET.sub("]", line)
            for m in MD_PATH.finditer(line):
                check_target(f"{path}:{number}", m.group(1), (m.group(2) or "#")[1:], problems)
    report(problems, "references to documentation that does not exist")


def test_no_reference_outside_the_repository():
    """No "SPEC section N" (the design document outside the repository),
    no ../shared, no README section by name.  Files the lead's refactor
    owns may appear here until that merge."""
    problems = []
    files = [p for p in text_files() if p != SELF]
    files += [p for p in doc_pages() if p not in files]
    for path in files:
        for number, line in enumerate(read_lines(path), 1):
            if OLD_SPEC.search(line):
                problems.append(f"{path}:{number}: cites the external specification: "
                                f"{line.strip()[:100]!r} (cite doc/*.md#anchor instead)")
            if OUTSIDE.search(line):
                problems.append(f"{path}:{number}: names a file outside the repository: "
                                f"{line.strip()[:100]!r}")
            if README_SECTION.search(line):
                problems.append(f"{path}:{number}: cites a README section by name: "
                                f"{line.strip()[:100]!r} (cite doc/*.md#anchor instead)")
    report(problems, "references outside the repository")


def test_markdown_links_resolve():
    """Every relative link and image of the README and the manual reaches
    a file, and a heading when it has an anchor."""
    problems = []
    for page in doc_pages():
        here = os.path.dirname(page)
        for number, line in prose_lines(read_lines(page)):
            targets = LINK_TARGET.findall(line) + HTML_REF.findall(line)
            m = LINK_DEF.match(line)
            if m:
                targets.append(m.group(1))
            for target in targets:
                if EXTERNAL.match(target):
                    continue
                path, _, anchor = target.partition("#")
                path = urllib.parse.unquote(path)
                resolved = os.path.normpath(os.path.join(here, path)) if path else page
                check_target(f"{page}:{number}: link {target}", resolved, anchor, problems)
    report(problems, "broken links")


def defined_keys():
    keys = set()
    for line in read_lines("doc/references.md"):
        m = re.match(r"^#{2,3}\s+\[([^\]]+)\]\s*$", line)
        if m:
            keys.add(m.group(1))
    return keys


def test_citation_keys_are_defined():
    """[Paper], [Horn], ... in the code and the docs: each is a heading of
    doc/references.md."""
    keys = defined_keys()
    assert {"Paper", "Horn"} <= keys, f"doc/references.md defines {sorted(keys)}"
    problems = []
    sources = [(p, enumerate(read_lines(p), 1)) for p in text_files()
               if p != SELF and not p.endswith(".md")]
    sources += [(p, prose_lines(read_lines(p))) for p in doc_pages()]
    sources += [(p, prose_lines(read_lines(p))) for p in text_files()
                if p.endswith(".md") and p not in PAGES]
    for path, lines in sources:
        for number, line in lines:
            for key in KEY.findall(line):
                if key not in keys and key not in NOT_KEYS:
                    problems.append(f"{path}:{number}: [{key}] is not defined in "
                                    f"doc/references.md (defined: {', '.join(sorted(keys))})")
    report(problems, "undefined citation keys")


def test_readme_is_a_front_page():
    lines = read_lines("README.md")
    count = len(lines) - (lines[-1] == "")
    assert count < 300, f"README.md has {count} lines: keep it under 300 (the manual is doc/)"


def test_slug_follows_github():
    """The anchor rule the checks above rely on."""
    assert slug("RKL2 super-steps") == "rkl2-super-steps"
    assert slug("Time to solution: Euler against RKL2") == "time-to-solution-euler-against-rkl2"
    assert slug("[grid]") == "grid"
    assert slug("Making a video: the door at 480 x 320") == "making-a-video-the-door-at-480-x-320"
    assert slug("Signals: Ctrl-C and SIGTERM") == "signals-ctrl-c-and-sigterm"
    assert slug("The `max_time` key") == "the-max_time-key"
