"""The declaration rule a run used, for the plots: read from an hstpfd
configuration file (key = value, docs/daemon.md), else the library's own
defaults (hstpf_config_default in lib/src), never a number of our own."""
import re
from pathlib import Path
from typing import Dict, Optional

from . import cli

ROOT = Path(__file__).resolve().parents[2]


def read_ini(path: str) -> Dict[str, str]:
    """key -> value of an hstpfd config file (sections ignored, '#' and ';'
    start comments). CliError(3) when it cannot be read."""
    out = {}
    for line in cli.read_text(path).splitlines():
        line = re.split(r"\s[#;]|^[#;]", line, maxsplit=1)[0].strip()
        if "=" in line and not line.startswith("["):
            k, _, v = line.partition("=")
            out[k.strip()] = v.strip()
    return out


def library_default(key: str, src: Path = ROOT / "lib" / "src") -> Optional[float]:
    """The value hstpf_config_default() gives `key` (`cfg->key = 0.99;` in
    lib/src/*.c), or None if this is not a source tree."""
    pat = re.compile(r"cfg->" + re.escape(key) + r"\s*=\s*([-+]?[0-9.]+(?:[eE][-+]?\d+)?)\s*;")
    for p in sorted(src.glob("*.c")) if src.is_dir() else ():
        m = pat.search(p.read_text())
        if m:
            return float(m.group(1))
    return None


def declaration(config: Optional[str] = None) -> dict:
    """{"threshold", "hold_s", "source"}: the run's declaration rule (values
    None when unknown: the plots then leave the line out)."""
    ini = read_ini(config) if config else {}
    out = {"source": Path(config).name if config and "declare_threshold" in ini else "library default"}
    for name, key in (("threshold", "declare_threshold"), ("hold_s", "declare_hold_s")):
        if key in ini:
            try:
                out[name] = float(ini[key])
            except ValueError as exc:
                raise cli.CliError(cli.EXIT_INPUT, f"{config}: {key} = {ini[key]!r} is not a number") from exc
        else:
            out[name] = library_default(key)
    return out
