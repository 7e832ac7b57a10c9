"""Table 1 of the paper (Davis coefficients of 17 train types), read from its
one copy, the C table in lib/src/train_types.c, when this package is imported.

The row index is what the CAN frames carry (DeclaredType, LeaderType) and the
order of the DBC's value table; tests/python/test_table1.py checks that the C
table, this parse of it and the DBC agree.
"""
import os
import re
from pathlib import Path
from typing import Optional, Tuple

Row = Tuple[str, float, float, float]

_NUM = r"([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)"
_ROW = re.compile(r'\{\s*"([^"]*)"\s*,\s*' + _NUM + r"\s*,\s*" + _NUM + r"\s*,\s*" + _NUM + r"\s*\}")


def c_path(path: Optional[str] = None) -> Path:
    """`path`, else $HSTPF_TRAIN_TYPES, else lib/src/train_types.c of the
    source tree this package lives in (an editable install)."""
    for p in (path, os.environ.get("HSTPF_TRAIN_TYPES")):
        if p:
            return Path(p)
    return Path(__file__).resolve().parents[2] / "lib" / "src" / "train_types.c"


def parse(text: str) -> Tuple[Row, ...]:
    """The rows of `hstpf_train_types[...] = { ... };` in C source text.
    ValueError when the initializer is absent or holds anything but
    {"name", c0, c1, c2} rows of plain numbers."""
    text = re.sub(r"/\*.*?\*/|//[^\n]*", " ", text, flags=re.S)
    m = re.search(r"hstpf_train_types\s*\[[^\]]*\]\s*=\s*\{(.*?)\}\s*;", text, re.S)
    if m is None:
        raise ValueError("no hstpf_train_types initializer")
    body = m.group(1)
    rows = tuple((r[0], float(r[1]), float(r[2]), float(r[3])) for r in _ROW.findall(body))
    rest = _ROW.sub("", body).replace(",", "").strip()
    if rest or not rows:
        raise ValueError(f"hstpf_train_types: not a plain table of rows near {rest[:40]!r}")
    return rows


def load(path: Optional[str] = None) -> Tuple[Row, ...]:
    p = c_path(path)
    try:
        return parse(p.read_text())
    except OSError as exc:
        raise ImportError(f"Table 1 is read from {p} ({exc.strerror}): run from a source tree (pip install -e "
                          "tools) or set HSTPF_TRAIN_TYPES to lib/src/train_types.c") from exc


TABLE1: Tuple[Row, ...] = load()
