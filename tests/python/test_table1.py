"""Table 1 has one source, lib/src/train_types.c: the Python table is parsed
from it, the compiled C table must equal that parse, and the DBC's value
tables of type names (DeclaredType, LeaderType) must name the same rows in
the same order. Fails when any of them drifts."""
import re
import shutil
import subprocess
from pathlib import Path

import cantools
import pytest

from hstpf_tools import table1
from hstpf_tools.frames import TYPE_CUSTOM, TYPE_NONE, type_index, type_name
from hstpf_tools.model import theta_for

ROOT = Path(__file__).resolve().parents[2]
C_FILE = ROOT / "lib" / "src" / "train_types.c"


def n_types_in_header() -> int:
    m = re.search(r"#define\s+HSTPF_N_TRAIN_TYPES\s+(\d+)", (ROOT / "lib/include/hstpf/hstpf.h").read_text())
    return int(m.group(1))


@pytest.fixture(scope="module")
def c_table(tmp_path_factory):
    """The table as the C compiler sees it: train_types.c compiled and printed
    with %.17g (every double exactly)."""
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no C compiler")
    d = tmp_path_factory.mktemp("t1")
    (d / "dump.c").write_text(
        '#include <stdio.h>\n#include "hstpf/hstpf.h"\n'
        "int main(void) { int i; for (i = 0; i < HSTPF_N_TRAIN_TYPES; ++i) {\n"
        '  const hstpf_theta_t *t = &hstpf_train_types[i];\n'
        '  printf("%s|%.17g|%.17g|%.17g\\n", t->name, t->c0, t->c1, t->c2); } return 0; }\n')
    subprocess.run([cc, "-std=c99", "-Wall", "-Werror", f"-I{ROOT / 'lib/include'}", str(d / "dump.c"), str(C_FILE),
                    "-o", str(d / "dump")], check=True)
    out = subprocess.run([str(d / "dump")], check=True, capture_output=True, text=True).stdout
    return tuple((n, float(a), float(b), float(c)) for n, a, b, c in (line.split("|") for line in out.splitlines()))


def test_python_table_is_the_compiled_c_table(c_table):
    assert table1.TABLE1 == c_table
    assert len(c_table) == n_types_in_header() == 17


def test_the_paper_values_of_a_few_rows():
    # hand-copied from the paper's Table 1: catches a wrong column order in the parse
    assert table1.TABLE1[2] == ("CRH3", 0.79, 0.0064, 0.000115)
    assert table1.TABLE1[16] == ("China Star", 1.16, 0.00534, 0.000182)
    assert theta_for("SS8").c2 == 0.000426 and theta_for("ss4").name == "SS1/SS3/SS4"


def _key(name: str) -> str:
    """DBC choice names cannot hold '/' or spaces: compare letters and digits."""
    return re.sub(r"[^a-z0-9]", "", name.lower())


@pytest.mark.parametrize("signal", ["DeclaredType", "LeaderType"])
def test_dbc_value_table_names_the_same_rows(signal):
    db = cantools.database.load_file(str(ROOT / "port" / "dbc" / "hstpf.dbc"))
    sig = db.get_message_by_name("EstType").get_signal_by_name(signal)
    choices = {int(k): str(v) for k, v in sig.choices.items()}
    expect = {i: row[0] for i, row in enumerate(table1.TABLE1)}
    assert {i: _key(n) for i, n in choices.items() if i < 250} == {i: _key(n) for i, n in expect.items()}
    assert _key(choices[TYPE_CUSTOM]) == "custom" and _key(choices[TYPE_NONE]) == "none"
    assert set(choices) == set(expect) | {TYPE_CUSTOM, TYPE_NONE}
    assert all(type_name(i) == expect[i] for i in expect) and type_index(expect[4]) == 4


def test_parse_rejects_a_table_it_cannot_read():
    ok = 'const hstpf_theta_t hstpf_train_types[2] = {\n {"A", 1.0, 2e-3, .5}, /* x */\n {"B", 1, 2, 3},\n};'
    assert table1.parse(ok) == (("A", 1.0, 0.002, 0.5), ("B", 1.0, 2.0, 3.0))
    with pytest.raises(ValueError):
        table1.parse(ok.replace("2e-3", "C1_A"))  # a macro: the parse would be wrong, so it refuses
    with pytest.raises(ValueError):
        table1.parse("int x;")


def test_no_other_copy_in_the_tools():
    """No Python file under tools/ spells out a Table 1 row again (CRH3's c1
    and c2 on one line, or SS8's)."""
    hits = []
    for p in (ROOT / "tools").rglob("*.py"):
        for n, line in enumerate(p.read_text().splitlines(), 1):
            if ("0.0064" in line and "0.000115" in line) or ("0.0035" in line and "0.000426" in line):
                hits.append(f"{p.relative_to(ROOT)}:{n}")
    assert hits == []
