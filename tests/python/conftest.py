# SPDX-License-Identifier: BSD-3-Clause
"""The Python module's tests import `sandslide` as a user does; when it
is not on the path (no PYTHONPATH=python, no install), this checkout's
python/ is put first, so `pytest tests/python` works from a checkout."""
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
try:
    import sandslide  # noqa: F401
except ImportError:
    sys.path.insert(0, os.path.join(ROOT, "python"))
