"""The C library (runtime/c) on its own: tests/c/test_gac.c, hand-written toy models (a bouncing ball against
its closed form for each integrator, a point in a box with e = 1, the refusals), compiled strictly and run
with no Python in the loop."""
import shutil
import subprocess
from pathlib import Path

import pytest

from runtime.compile import LIBRARY_DIR, library_sources

TEST = Path(__file__).resolve().parent / "c" / "test_gac.c"
STRICT = ["-std=c99", "-Wall", "-Wextra", "-pedantic", "-Werror", "-O2"]


@pytest.fixture(scope="module")
def test_gac(tmp_path_factory):
    if shutil.which("gcc") is None:
        pytest.skip("gcc is not installed: the C unit test of the library needs a C compiler")
    exe = tmp_path_factory.mktemp("clib") / "test_gac"
    subprocess.run(["gcc", *STRICT, "-I", str(LIBRARY_DIR), str(TEST), *map(str, library_sources()), "-lm",
                    "-o", str(exe)], check=True)
    return exe


def test_library_unit_test_passes(test_gac):
    result = subprocess.run([str(test_gac)], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stdout + result.stderr
    checks, failed = (int(word) for word in result.stdout.split()[-4::2])
    assert failed == 0 and checks > 150, result.stdout


def test_library_unit_test_can_fail(test_gac):
    """With --break one expected impact time is off by 1e-9 s: the closed-form checks must catch it."""
    result = subprocess.run([str(test_gac), "--break"], capture_output=True, text=True, timeout=120)
    assert result.returncode == 1
    assert "FAIL" in result.stdout and "impact 1 at" in result.stdout


def test_library_is_strict_c99_at_every_level(tmp_path):
    """No warning at -O0 and -O3 either, and the headers compile as C++."""
    if shutil.which("gcc") is None:
        pytest.skip("gcc is not installed")
    for level in ("-O0", "-O3"):
        for source in library_sources():
            subprocess.run(["gcc", *STRICT[:-1], level, "-c", str(source), "-o", str(tmp_path / "x.o")], check=True)
    if shutil.which("g++"):
        (tmp_path / "use.cpp").write_text('#include "gac.h"\nint main() { gac_options o; gac_default_options(&o);'
                                          ' return o.method == GAC_METHOD_DOPRI5 ? 0 : 1; }\n')
        subprocess.run(["g++", "-std=c++11", "-Wall", "-Wextra", "-pedantic", "-Werror", "-fsyntax-only", "-I",
                        str(LIBRARY_DIR), str(tmp_path / "use.cpp")], check=True)
