"""`python -m codegen`: the output folder is checked before any work, scene files default to build/,
and an unusable cache directory is a clear error."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

from runtime.compile import library_files

ROOT = Path(__file__).resolve().parent.parent
FIX = "give a directory that exists or can be created"

SCENE_FILE = """name = "tiny"
[[links]]
length = 1.0
mu = 1.0
[walls]
x2_min = -5.0
"""


def run_cli(*args, cwd, cache):
    env = dict(os.environ, GIBBS_APPELL_CACHE=str(cache), PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, "-m", "codegen", *args], capture_output=True, text=True, cwd=cwd,
                          env=env)


def assert_refused(result, message: str, cache: Path) -> None:
    assert result.returncode == 2
    assert result.stderr == f"error: {message}\n"          # one line, no traceback, no progress
    assert result.stdout == ""
    assert not cache.exists()                              # no generation work was done


def test_out_that_is_an_existing_file_is_refused(tmp_path):
    target = tmp_path / "out.txt"
    target.write_text("keep me")
    result = run_cli("--links", "1", "--out", str(target), cwd=tmp_path, cache=tmp_path / "cache")
    assert_refused(result, f"--out: {target} exists and is not a directory; {FIX}", tmp_path / "cache")
    assert target.read_text() == "keep me"


def test_out_under_a_file_is_refused(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    target = blocker / "sub" / "dir"
    result = run_cli("--links", "1", "--out", str(target), cwd=tmp_path, cache=tmp_path / "cache")
    assert_refused(result, f"--out: cannot create {target}: {blocker} is a file, not a directory; {FIX}",
                   tmp_path / "cache")


@pytest.mark.skipif(hasattr(os, "geteuid") and os.geteuid() == 0,
                    reason="root writes into a read-only directory, so permissions cannot make --out unusable")
def test_out_without_write_permission_is_refused(tmp_path):
    folder = tmp_path / "read-only"
    folder.mkdir()
    folder.chmod(0o500)
    try:
        result = run_cli("--links", "1", "--out", str(folder / "models"), cwd=tmp_path, cache=tmp_path / "cache")
        assert_refused(result, f"--out: cannot create {folder / 'models'}: the directory {folder} is not writable; "
                               f"{FIX}", tmp_path / "cache")
        assert list(folder.iterdir()) == []
    finally:
        folder.chmod(0o700)


def test_unusable_cache_directory_is_refused_before_writing(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    result = run_cli("--links", "1", "--out", str(tmp_path / "out"), cwd=tmp_path, cache=blocker / "cache")
    assert result.returncode == 2
    assert result.stderr == (f"error: cache directory {str(blocker / 'cache')!r} (from GIBBS_APPELL_CACHE) cannot "
                             f"be created ({blocker} is a file, not a directory); set GIBBS_APPELL_CACHE to a "
                             "writable directory\n")
    assert not (tmp_path / "out").exists()


def test_scene_file_defaults_to_build_and_links_to_generated(tmp_path):
    (tmp_path / "tiny.toml").write_text(SCENE_FILE)
    result = run_cli("--scene", "tiny.toml", "--no-compile", cwd=tmp_path, cache=tmp_path / "cache")
    assert result.returncode == 0, result.stderr
    library = [p.name for p in library_files()]          # the C library is written beside the model
    assert sorted(p.name for p in (tmp_path / "build").iterdir()) == sorted(["tiny.c", "tiny.h", *library])
    assert not (tmp_path / "generated").exists()
    result = run_cli("--links", "1", "--no-compile", cwd=tmp_path, cache=tmp_path / "cache")
    assert result.returncode == 0, result.stderr
    assert sorted(p.name for p in (tmp_path / "generated").iterdir()) == sorted(["chain1.c", "chain1.h", *library])


def test_help_states_the_default_folders(tmp_path):
    result = run_cli("--help", cwd=tmp_path, cache=tmp_path / "cache")
    assert result.returncode == 0
    text = " ".join(result.stdout.split())
    assert "default: generated/ for --links and shipped scenes, build/ for a scene file" in text


def test_unwritable_out_message_when_permissions_apply(tmp_path, monkeypatch):
    """The same check as above, run by any user: os.access reports no write permission."""
    from codegen.cli import out_dir_problem
    monkeypatch.setattr(os, "access", lambda path, mode: False)
    assert out_dir_problem(str(tmp_path)) == f"--out: the directory {tmp_path} is not writable; {FIX}"
    assert out_dir_problem(str(tmp_path / "new")) == \
        f"--out: cannot create {tmp_path / 'new'}: the directory {tmp_path} is not writable; {FIX}"


def test_ops_is_a_study(tmp_path):
    """The operation-count study is python -m studies ops; the old form says so in one line, before any work."""
    result = run_cli("ops", "--links", "1-2", cwd=tmp_path, cache=tmp_path / "cache")
    assert_refused(result, "'ops' is a study: run python -m studies ops --links 1-2", tmp_path / "cache")


def test_tangent_kernels_on_request(capsys):
    """--tangent adds the tangent kernels (and straight-line forward dynamics for a long chain); with --rolled it is
    refused naming both options."""
    from codegen.cli import main
    assert main(["--links", "10", "--explain"]) == 0
    out = capsys.readouterr().out
    assert "tangent kernels (exact derivatives): left out (--tangent adds them)" in out and "loops over links" in out
    assert main(["--links", "10", "--explain", "--tangent"]) == 0
    out = capsys.readouterr().out
    assert "tangent kernels (exact derivatives): generated (--tangent)" in out
    assert "straight-line code per link (--tangent: the tangent kernels need it)" in out
    assert main(["--links", "10", "--rolled", "--tangent", "--no-compile"]) == 2
    assert "error: --tangent: the rolled forward dynamics (rolled=True" in capsys.readouterr().err


def test_explain_says_what_a_mounted_base_holds(capsys):
    from codegen.cli import main
    assert main(["--scene", "mounted-arm", "--explain"]) == 0
    out = capsys.readouterr().out
    assert "the model keeps 2 of 8 coordinates" in out
    assert ("base fixed: O_1 held at (1, 0, 0), link 1 welded to the box, so theta_-1, theta_0, theta_1, X1, X2, X3 "
            "are not coordinates") in out
