"""--standalone: the model, the C library (the hybrid loop), an example program and build files, with no
Python."""
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from codegen.scene import load_scene
from runtime import simulate
from runtime.compile import library_files
from conftest import sanitized_build

ROOT = Path(__file__).resolve().parent.parent
STRICT = "-std=c99 -O2 -Wall -Wextra -pedantic -Werror"


@pytest.fixture(scope="module")
def case1_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("standalone")
    subprocess.run([sys.executable, "-m", "codegen", "--scene", "paper-case1", "--out", str(out), "--standalone",
                    "--no-compile"], check=True, cwd=ROOT, capture_output=True)
    return out


def impact_times(stdout: str) -> list[float]:
    return [float(line.split()[1]) for line in stdout.splitlines() if re.match(r"^\s*\d+ \d", line)]


def library(folder: Path) -> list[str]:
    """The library's sources copied beside the model."""
    return sorted(str(path) for path in folder.glob("gac_*.c"))


def test_standalone_files_are_written(case1_dir):
    names = sorted(p.name for p in case1_dir.iterdir())
    copies = sorted(p.name for p in library_files())
    assert names == sorted(["CMakeLists.txt", "Makefile", "paper_case1.c", "paper_case1.h", "paper_case1_example.c",
                            *copies])
    assert {"gac.h", "gac_sim.c"} <= set(copies)
    for path in library_files():
        assert (case1_dir / path.name).read_text() == path.read_text()


def test_example_builds_strictly_and_matches_the_python_runtime(case1_dir, compiled):
    subprocess.run(["make", "-s", f"CFLAGS={STRICT}"], cwd=case1_dir, check=True)
    result = subprocess.run(["./paper_case1_example", "1.5", "dopri5", "1e-10"], cwd=case1_dir,
                            capture_output=True, text=True, check=True)
    c_times = impact_times(result.stdout)
    python = simulate(compiled(load_scene("paper-case1"), specialise=True), 1.5, rtol=1e-10, atol=1e-12, t_eval=[])
    assert len(c_times) == len(python.impacts) == 7
    assert max(abs(a - b.t) for a, b in zip(c_times, python.impacts)) < 1e-12
    assert "O1/x2_min" in result.stdout and "O5/x2_min" in result.stdout


def test_cmake_build(case1_dir, tmp_path):
    cmake = shutil.which("cmake") or str(Path(sys.executable).parent / "cmake")
    build = tmp_path / "build"
    subprocess.run([cmake, "-S", str(case1_dir), "-B", str(build)], check=True, capture_output=True)
    subprocess.run([cmake, "--build", str(build)], check=True, capture_output=True)
    result = subprocess.run([str(build / "paper_case1_example"), "0.3"], capture_output=True, text=True, check=True)
    assert len(impact_times(result.stdout)) == 1


def test_cmake_package_is_found_by_a_consumer(case1_dir, tmp_path, compiled):
    """cmake --install gives a CMake package: a separate project finds it with find_package and links
    paper_case1::paper_case1; its first impact is the Python runtime's."""
    cmake = shutil.which("cmake") or str(Path(sys.executable).parent / "cmake")
    build, prefix, consumer = tmp_path / "build", tmp_path / "prefix", tmp_path / "consumer"
    subprocess.run([cmake, "-S", str(case1_dir), "-B", str(build), "-DPAPER_CASE1_BUILD_EXAMPLE=OFF",
                    f"-DCMAKE_C_FLAGS={STRICT}"], check=True, capture_output=True)
    subprocess.run([cmake, "--build", str(build)], check=True, capture_output=True)
    subprocess.run([cmake, "--install", str(build), "--prefix", str(prefix)], check=True, capture_output=True)
    assert (prefix / "include" / "paper_case1" / "paper_case1.h").exists()
    assert not (build / "paper_case1_example").exists()
    consumer.mkdir()
    (consumer / "CMakeLists.txt").write_text(
        "cmake_minimum_required(VERSION 3.14)\nproject(consumer C)\n"
        "find_package(paper_case1 0.1.0 CONFIG REQUIRED)\n"
        "add_executable(first_impact main.c)\ntarget_link_libraries(first_impact PRIVATE paper_case1::paper_case1)\n")
    (consumer / "main.c").write_text(
        '#include <paper_case1.h>\n#include <stdio.h>\n'
        'int main(void) { paper_case1_options opt; paper_case1_sim sim; paper_case1_impact_record rec;\n'
        '  double p[PAPER_CASE1_NPARAM], q[PAPER_CASE1_NQ], qd[PAPER_CASE1_NQ]; int code;\n'
        '  paper_case1_default_options(&opt); opt.rtol = 1e-10; opt.atol = 1e-12;\n'
        '  paper_case1_default_parameters(p); paper_case1_initial_state(q, qd);\n'
        '  paper_case1_sim_init(&sim, 0.0, q, qd, p, &opt);\n'
        '  code = paper_case1_sim_advance(&sim, 0.3, 0, 0, 0, 0, &rec);\n'
        '  printf("%.15f\\n", rec.base.t); return code == GAC_SIM_IMPACT ? 0 : 1; }\n')
    subprocess.run([cmake, "-S", str(consumer), "-B", str(consumer / "build"), f"-DCMAKE_PREFIX_PATH={prefix}",
                    f"-DCMAKE_C_FLAGS={STRICT}"], check=True, capture_output=True)
    subprocess.run([cmake, "--build", str(consumer / "build")], check=True, capture_output=True)
    result = subprocess.run([str(consumer / "build" / "first_impact")], capture_output=True, text=True, check=True)
    python = simulate(compiled(load_scene("paper-case1"), specialise=True), 0.3, rtol=1e-10, atol=1e-12, t_eval=[])
    assert abs(float(result.stdout) - python.impacts[0].t) < 1e-12


def test_header_compiles_as_cxx_and_links_from_cxx(case1_dir, tmp_path):
    (tmp_path / "use.cpp").write_text(
        '#include "paper_case1.h"\n#include <cstdio>\n'
        'int main() { paper_case1_options opt; paper_case1_sim sim; paper_case1_impact_record rec;\n'
        '  double p[PAPER_CASE1_NPARAM], q[PAPER_CASE1_NQ], qd[PAPER_CASE1_NQ];\n'
        '  paper_case1_default_options(&opt); paper_case1_default_parameters(p); paper_case1_initial_state(q, qd);\n'
        '  paper_case1_sim_init(&sim, 0.0, q, qd, p, &opt);\n'
        '  int code = paper_case1_sim_advance(&sim, 0.3, 0, 0, 0, 0, &rec);\n'
        '  std::printf("%d %.12f\\n", code, rec.base.t); return code == GAC_SIM_IMPACT ? 0 : 1; }\n')
    objects = []
    for source in [str(case1_dir / "paper_case1.c"), *library(case1_dir)]:
        objects.append(str(tmp_path / (Path(source).stem + ".o")))
        subprocess.run(["gcc", *STRICT.split(), "-c", source, "-o", objects[-1]], check=True)
    subprocess.run(["g++", "-std=c++11", "-Wall", "-Wextra", "-pedantic", "-Werror", "-I", str(case1_dir),
                    str(tmp_path / "use.cpp"), *objects, "-lm", "-o", str(tmp_path / "use")], check=True)
    out = subprocess.run([str(tmp_path / "use")], capture_output=True, text=True, check=True).stdout
    assert out.startswith("2 0.2473096834")


def test_example_is_clean_under_sanitizers(case1_dir, tmp_path):
    exe = sanitized_build(case1_dir, [case1_dir / "paper_case1.c", case1_dir / "paper_case1_example.c"], "asan")
    for method in ("dopri5", "dop853", "rk4"):
        result = subprocess.run([str(exe), "1.5", method, "1e-3" if method == "rk4" else "1e-8"], capture_output=True,
                                text=True, env=dict(os.environ, ASAN_OPTIONS="detect_leaks=1"))
        assert result.returncode == 0, result.stderr
        assert "runtime error" not in result.stderr and len(impact_times(result.stdout)) == 7


@pytest.mark.skipif(shutil.which("valgrind") is None, reason="valgrind is not installed: the memory check "
                                                            "runs only where it is")
def test_example_is_clean_under_valgrind(case1_dir):
    subprocess.run(["make", "-s", f"CFLAGS={STRICT}"], cwd=case1_dir, check=True)
    result = subprocess.run(["valgrind", "--error-exitcode=9", "--leak-check=full", "-q", "./paper_case1_example",
                             "0.6"], cwd=case1_dir, capture_output=True, text=True)
    assert result.returncode == 0, result.stderr


def test_driven_example_with_a_pd_controller_matches_the_python_runtime(tmp_path):
    """The example's C controller (sim_set_controller) and the same PD law as a Python function agree."""
    subprocess.run([sys.executable, "-m", "codegen", "--scene", "driven-fold", "--out", str(tmp_path), "--standalone",
                    "--no-compile"], check=True, cwd=ROOT, capture_output=True)
    subprocess.run(["make", "-s", f"CFLAGS={STRICT}"], cwd=tmp_path, check=True)
    result = subprocess.run(["./driven_fold_example", "1.5", "dop853", "1e-12", "--pd", "5", "1"], cwd=tmp_path,
                            capture_output=True, text=True, check=True)
    c_times = impact_times(result.stdout)
    start = load_scene("driven-fold").q0

    def pd(t, q, qd):        # theta_2, theta_3 are q[3], q[4] of the full layout
        return -5.0 * (q[3:5] - start[3:5]) - 1.0 * qd[3:5]
    python = simulate("driven-fold", 1.5, u=pd, method="dop853", rtol=1e-12, atol=1e-14, t_eval=[])
    assert len(c_times) == len(python.impacts) >= 5
    assert max(abs(a - b.t) for a, b in zip(c_times, python.impacts)) < 1e-9
    work = float(re.search(r"work of the inputs (\S+) J", result.stdout).group(1))
    assert work == pytest.approx(python.work_input, rel=1e-8)
    bad = subprocess.run(["./driven_fold_example", "1", "--pd", "1", "-2"], cwd=tmp_path, capture_output=True, text=True)
    assert bad.returncode == 2 and "--pd KD: got '-2', allowed a finite gain >= 0" in bad.stderr
