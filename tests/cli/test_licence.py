# SPDX-License-Identifier: BSD-3-Clause
"""The licence (issue 36, item 9): BSD-3-Clause in LICENSE, in the first
comment of every source file (its SPDX identifier), in the README, in the
Python package's metadata and in the man page."""
import os
import re
import subprocess

import pytest

from conftest import ROOT

TAG = "SPDX-License-Identifier: BSD-3-Clause"
# what counts as source: code, build files and templates (not data: cases,
# rasters, fuzz corpora, Markdown)
SOURCE = re.compile(r"(\.(c|h|py|sh|js|awk|toml)|/Makefile|^Makefile|\.pc\.in|\.1\.in)$")


def tracked():
    r = subprocess.run(["git", "-C", ROOT, "ls-files"], capture_output=True, text=True)
    if r.returncode:
        pytest.skip("not a git checkout: no list of the tracked files")
    return r.stdout.split()


def test_every_source_file_names_the_licence_in_its_first_comment():
    missing = []
    for f in tracked():
        if not SOURCE.search(f) or (f.startswith("tests/fuzz/") and not f.endswith((".c", ".h"))):
            continue
        with open(os.path.join(ROOT, f), encoding="utf-8") as fh:
            head = [fh.readline() for _ in range(3)]
        if not any(TAG in line for line in head):
            missing.append(f)
    assert not missing, f"{len(missing)} source files without '{TAG}' in their first " \
        f"three lines: " + ", ".join(missing[:20])


def test_the_licence_file_the_readme_python_and_the_man_page_agree():
    text = open(os.path.join(ROOT, "LICENSE")).read()
    assert text.startswith("BSD 3-Clause License") and "Neither the name of" in text, \
        "LICENSE is not the BSD-3-Clause text"
    readme = open(os.path.join(ROOT, "README.md")).read()
    section = readme.split("## Licence", 1)[1]
    assert "BSD-3-Clause" in section and "LICENSE" in section, \
        f"the README's licence does not name BSD-3-Clause and LICENSE:\n{section[:300]}"
    pyproject = open(os.path.join(ROOT, "pyproject.toml")).read()
    assert re.search(r'^license = \{text = "BSD-3-Clause"\}', pyproject, re.M), \
        "pyproject.toml's [project] has no license = {text = \"BSD-3-Clause\"}"
    man = open(os.path.join(ROOT, "doc", "sandslide.1.in")).read()
    assert re.search(r"^\.SH LICEN[CS]E\n(.*\n)*?BSD-3-Clause", man, re.M), \
        "the man page has no LICENSE section naming BSD-3-Clause"
