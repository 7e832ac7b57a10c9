"""Shared fixtures of the Python tests (tools/hstpf_tools, port/codec)."""
import os
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def root() -> Path:
    return ROOT


@pytest.fixture(scope="session")
def codec_dump(tmp_path_factory) -> str:
    """The C frame dump program: $HSTPF_CODEC_DUMP, else the CMake build's
    in $HSTPF_BUILD_DIR, else compiled here with the system cc."""
    exe = os.environ.get("HSTPF_CODEC_DUMP")
    if exe:
        return exe
    build = os.environ.get("HSTPF_BUILD_DIR")
    if build:
        for rel in ("port/codec/tests/hstpf_codec_dump", "tests/codec/hstpf_codec_dump"):
            if (Path(build) / rel).is_file():
                return str(Path(build) / rel)
    cc = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc")
    if cc is None:
        pytest.skip("no C compiler and no HSTPF_CODEC_DUMP")
    out = tmp_path_factory.mktemp("codec") / "hstpf_codec_dump"
    codec = ROOT / "port" / "codec"
    srcs = [ROOT / "tests" / "codec" / "codec_dump.c", codec / "hstpf_e2e.c",
            codec / "generated" / "hstpf_can.c", codec / "generated" / "hstpf_frames.c"]
    subprocess.run([cc, "-std=c99", "-O1", "-Wall", "-Wextra", "-Werror", f"-I{codec}", f"-I{codec / 'generated'}",
                    *map(str, srcs), "-o", str(out), "-lm"], check=True)
    return str(out)
