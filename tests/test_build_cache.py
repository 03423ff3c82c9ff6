"""The build cache: corrupted entries are reported in one line and rebuilt, an unusable cache
directory is a clear CacheError, load_model rejects what is not a scene, reuses a loaded model by
name, and shares its cache with `python -m codegen`."""
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import codegen.cache
import codegen.pipeline
import runtime.compile
import runtime.model
from codegen.artifact import text_digest
from codegen.cache import CacheError, generation_key
from codegen.scene import default_scene
from conftest import cache_with_library
from runtime import load_model
from runtime.compile import build_key, module_files, verify_module

ROOT = Path(__file__).resolve().parent.parent
SCENE = default_scene(1)
NOTICE = "cache: rebuilding corrupted entry "
FIX = "set GIBBS_APPELL_CACHE to a writable directory"


def entries(folder: Path) -> tuple[Path, Path, Path]:
    """The gen json, the module and its sidecar of SCENE's model in ``folder``."""
    gen = folder / f"gen_{generation_key(SCENE)}.json"
    payload = json.loads(gen.read_text())["payload"]
    module, sidecar = module_files(folder, f"_gac_{build_key(text_digest(payload['header'], payload['source'], payload['cdef']), ('-O2',))}")
    return gen, module, sidecar


def assert_valid(folder: Path) -> None:
    gen, module, sidecar = entries(folder)
    payload, problem = codegen.cache._read_generated(gen, generation_key(SCENE), SCENE.name)
    assert payload is not None and problem is None
    assert verify_module(module, sidecar) is None


@pytest.fixture(scope="module")
def pristine(tmp_path_factory):
    """A cache holding SCENE's generated text and compiled module, built in a separate process."""
    folder = cache_with_library(tmp_path_factory.mktemp("pristine") / "cache")
    env = dict(os.environ, GIBBS_APPELL_CACHE=str(folder), PYTHONPATH=str(ROOT))
    code = "from runtime import load_model; from codegen.scene import default_scene; load_model(default_scene(1))"
    subprocess.run([sys.executable, "-c", code], env=env, check=True, cwd=ROOT)
    assert_valid(folder)
    return folder


@pytest.fixture
def cache(pristine, tmp_path, monkeypatch):
    """A private copy of the pristine cache, with nothing of it imported in this process yet."""
    folder = tmp_path / "cache"
    shutil.copytree(pristine, folder)
    monkeypatch.setenv("GIBBS_APPELL_CACHE", str(folder))
    monkeypatch.setattr(runtime.compile, "_LOADED", {})
    monkeypatch.setattr(runtime.compile, "_FAILED", set())
    return folder


def _rewrite_gen(path: Path, change) -> None:
    data = json.loads(path.read_text())
    change(data)
    path.write_text(json.dumps(data))


def _foreign_module(module: Path, sidecar: Path) -> None:
    """A loadable shared object that is not this model, with a sidecar that matches it."""
    import _cffi_backend
    shutil.copyfile(_cffi_backend.__file__, module)
    sidecar.write_text(f"{codegen.cache.sha256_of(module.read_bytes())}  {module.name}\n")


CORRUPTIONS = {
    # name: (what to do to (gen, module, sidecar), corrupted file, reason in the notice)
    "empty .so": (lambda g, m, s: m.write_bytes(b""), "module", "sha256 mismatch"),
    "random .so": (lambda g, m, s: m.write_bytes(os.urandom(4096)), "module", "sha256 mismatch"),
    "truncated .so": (lambda g, m, s: m.write_bytes(m.read_bytes()[:1000]), "module", "sha256 mismatch"),
    "sidecar missing": (lambda g, m, s: s.unlink(), "module", "sha256 sidecar missing"),
    "sidecar garbage": (lambda g, m, s: s.write_text("not a hash\n"), "module", "sha256 sidecar malformed"),
    "another module, matching sidecar": (lambda g, m, s: _foreign_module(m, s), "module", "import failed"),
    "directory for the .so": (lambda g, m, s: (m.unlink(), m.mkdir(), (m / "x").write_text("x")), "module",
                              "unreadable: Is a directory"),
    "directory for the sidecar": (lambda g, m, s: (s.unlink(), s.mkdir()), "module", "sha256 sidecar unreadable"),
    "directory for the gen json": (lambda g, m, s: (g.unlink(), g.mkdir()), "gen", "unreadable: Is a directory"),
    "garbage gen json": (lambda g, m, s: g.write_bytes(os.urandom(64)), "gen", "not valid JSON"),
    "gen json missing a key": (lambda g, m, s: _rewrite_gen(g, lambda d: d["payload"].pop("source")), "gen",
                               "missing key 'source'"),
    "gen json wrong hash": (lambda g, m, s: _rewrite_gen(g, lambda d: d.update(sha256="0" * 64)), "gen",
                            "sha256 mismatch"),
    "gen json edited source": (lambda g, m, s: _rewrite_gen(g, lambda d: d["payload"].update(source="int x;")),
                               "gen", "sha256 mismatch"),
}


@pytest.mark.parametrize("case", sorted(CORRUPTIONS))
def test_corrupted_entry_is_reported_once_and_rebuilt(cache, capsys, case):
    corrupt, which, reason = CORRUPTIONS[case]
    gen, module, sidecar = entries(cache)
    corrupt(gen, module, sidecar)
    capsys.readouterr()
    model = load_model(SCENE)
    assert model.forward_dynamics(model.q0, model.qd0)[-1] == pytest.approx(-9.81)   # free fall from rest
    err = capsys.readouterr().err
    name = (gen if which == "gen" else module).name
    assert err == f"{NOTICE}{name} ({reason})\n" or (
        reason == "import failed" and err.startswith(f"{NOTICE}{name} (import failed: ") and err.count("\n") == 1)
    assert_valid(cache)
    assert not [p for p in cache.iterdir() if p.name.endswith(".tmp") or p.is_dir()]   # no leftovers


def test_notice_goes_to_progress_when_given(cache, capsys):
    gen, _, _ = entries(cache)
    gen.write_text("{")
    capsys.readouterr()
    messages = []
    load_model(SCENE, progress=messages.append)
    assert f"{NOTICE}{gen.name} (not valid JSON)" in messages
    assert capsys.readouterr().err == ""


def test_good_entries_load_silently_without_derivation_or_build(cache, capsys, monkeypatch):
    monkeypatch.setattr(codegen.pipeline, "generate", _forbidden)
    monkeypatch.setattr(runtime.compile, "_build", _forbidden)
    capsys.readouterr()
    load_model(SCENE)
    assert capsys.readouterr().err == ""


def _forbidden(*args, **kwargs):
    raise AssertionError("the cache should have been used")


BUILD_ONE = ("from runtime import load_model; from codegen.scene import default_scene; "
             "m = load_model(default_scene(1)); print(m.forward_dynamics(m.q0, m.qd0)[-1])")


def test_eight_processes_build_one_model_into_an_empty_cache(tmp_path):
    folder = tmp_path / "cache"
    env = dict(os.environ, GIBBS_APPELL_CACHE=str(folder), PYTHONPATH=str(ROOT))
    procs = [subprocess.Popen([sys.executable, "-c", BUILD_ONE], env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True, cwd=ROOT) for _ in range(8)]
    for proc in procs:
        out, err = proc.communicate(timeout=600)
        assert proc.returncode == 0, err
        assert float(out) == pytest.approx(-9.81)
        assert NOTICE not in err
    names = sorted(p.name for p in folder.iterdir() if not p.name.startswith(".lock_"))
    gen, module, sidecar = entries(folder)
    library = [folder / name for name in names if name.startswith("gac_lib_")]    # the C library, compiled once
    assert len(library) == 1 and library[0].suffix == ".o"
    library_sidecar = folder / f"sha256_{library[0].stem}.txt"
    assert names == sorted([gen.name, module.name, sidecar.name, library[0].name, library_sidecar.name])   # one
    assert verify_module(library[0], library_sidecar) is None                    # entry each, no leftovers
    assert_valid(folder)


# -- an unusable cache directory ------------------------------------------------
def test_cache_dir_that_is_a_file(tmp_path, monkeypatch):
    target = tmp_path / "a-file"
    target.write_text("")
    monkeypatch.setenv("GIBBS_APPELL_CACHE", str(target))
    with pytest.raises(CacheError) as info:
        load_model(SCENE)
    assert str(info.value) == (f"cache directory {str(target)!r} (from GIBBS_APPELL_CACHE) is not a directory; "
                               f"{FIX}")


def test_cache_dir_under_a_file(tmp_path, monkeypatch):
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    monkeypatch.setenv("GIBBS_APPELL_CACHE", str(blocker / "sub"))
    with pytest.raises(CacheError) as info:
        codegen.cache.cache_dir()
    assert str(info.value) == (f"cache directory {str(blocker / 'sub')!r} (from GIBBS_APPELL_CACHE) cannot be "
                               f"created ({blocker} is a file, not a directory); {FIX}")
    assert isinstance(info.value, RuntimeError)


@pytest.mark.skipif(hasattr(os, "geteuid") and os.geteuid() == 0,
                    reason="root writes into a read-only directory, so permissions cannot make it unusable")
def test_cache_dir_without_write_permission(tmp_path, monkeypatch):
    folder = tmp_path / "read-only"
    folder.mkdir()
    folder.chmod(0o500)
    monkeypatch.setenv("GIBBS_APPELL_CACHE", str(folder))
    try:
        with pytest.raises(CacheError, match=r"is not writable \(Permission denied\); set GIBBS_APPELL_CACHE"):
            codegen.cache.cache_dir()
    finally:
        folder.chmod(0o700)


def test_cache_dir_where_writing_fails(tmp_path, monkeypatch):
    """The same check as above, run by any user: creating a file in the directory is refused."""
    def refuse(*args, **kwargs):
        raise PermissionError(13, "Permission denied")
    monkeypatch.setenv("GIBBS_APPELL_CACHE", str(tmp_path))
    monkeypatch.setattr(codegen.cache, "_WRITABLE", set())
    monkeypatch.setattr(codegen.cache.tempfile, "mkstemp", refuse)
    with pytest.raises(CacheError) as info:
        load_model(SCENE)
    assert str(info.value) == (f"cache directory {str(tmp_path)!r} (from GIBBS_APPELL_CACHE) is not writable "
                               f"(Permission denied); {FIX}")


# -- what load_model accepts ----------------------------------------------------------
@pytest.mark.parametrize("value,shown", [(42, "42 (int)"), (None, "None (NoneType)"), (3.5, "3.5 (float)")])
def test_load_model_names_a_bad_scene_argument(value, shown):
    with pytest.raises(TypeError) as info:
        load_model(value)
    assert str(info.value) == ("scene: expected a Scene, a shipped scene name or a path to a .toml/.json "
                               f"scene file, got {shown}")


SCENE_FILE = """name = "memo"
gravity = {g}
[[links]]
length = 1.0
mu = 1.0
[walls]
x2_min = -5.0
"""


@pytest.fixture
def builds(monkeypatch):
    """Stand-in for building a model: records (scene, options) and returns a new object each time."""
    made = []

    def build(scene, options, progress):
        made.append((scene, options))
        return object()
    monkeypatch.setattr(runtime.model, "_build_model", build)
    monkeypatch.setattr(runtime.model, "_MODELS", {})
    return made


def test_loaded_model_is_reused_until_its_file_changes(tmp_path, builds):
    path = tmp_path / "memo.toml"
    path.write_text(SCENE_FILE.format(g="9.81"))
    first = load_model(path)
    assert load_model(str(path)) is first                          # same file, as str or Path
    assert load_model(path, specialise=False) is not first         # other options, other model
    assert load_model(path, flags=["-O1"]) is not first
    assert load_model(path) is first and len(builds) == 3
    stat = path.stat()
    path.write_text(SCENE_FILE.format(g="1.62"))                   # same size, new content
    os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns + 1_000_000_000))
    second = load_model(path)
    assert second is not first and len(builds) == 4
    assert builds[0][0].gravity == 9.81 and builds[3][0].gravity == 1.62


def test_shipped_scene_by_name_is_loaded_once(builds):
    first = load_model("paper-case1")
    assert load_model("paper-case1") is first
    assert load_model(ROOT / "codegen" / "scenes" / "paper-case1.toml") is first
    assert len(builds) == 1


def test_reused_model_is_a_real_model(tmp_path, monkeypatch):
    monkeypatch.setenv("GIBBS_APPELL_CACHE", str(cache_with_library(tmp_path / "cache")))
    path = tmp_path / "memo.toml"
    path.write_text(SCENE_FILE.format(g="9.81"))
    model = load_model(path)
    monkeypatch.setattr(codegen.pipeline, "generate", _forbidden)
    monkeypatch.setattr(runtime.compile, "compile_model", _forbidden)
    assert load_model(path) is model
    assert model.forward_dynamics(model.q0, model.qd0)[-1] == pytest.approx(-9.81)


# -- one cache for the generator command line and load_model ---------------------------
def test_codegen_cli_fills_the_cache_load_model_reads(tmp_path, monkeypatch):
    folder = cache_with_library(tmp_path / "cache")
    env = dict(os.environ, GIBBS_APPELL_CACHE=str(folder), PYTHONPATH=str(ROOT))
    result = subprocess.run([sys.executable, "-m", "codegen", "--links", "1", "--out", str(tmp_path / "out")],
                            env=env, capture_output=True, text=True, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    before = {p.name: p.stat().st_mtime_ns for p in folder.iterdir()}
    assert_valid(folder)
    monkeypatch.setenv("GIBBS_APPELL_CACHE", str(folder))
    monkeypatch.setattr(runtime.compile, "_LOADED", {})            # the module must come from the disk cache
    monkeypatch.setattr(codegen.pipeline, "generate", _forbidden)
    monkeypatch.setattr(runtime.compile, "_build", _forbidden)
    model = load_model(default_scene(1))
    assert model.forward_dynamics(model.q0, model.qd0)[-1] == pytest.approx(-9.81)
    assert {p.name: p.stat().st_mtime_ns for p in folder.iterdir()} == before


def test_the_c_library_is_compiled_once_and_a_corrupted_object_rebuilt(tmp_path, monkeypatch):
    """The library's object is one cache entry per flags, reused as it is, and rebuilt (with the notice) when its
    sha256 no longer matches."""
    monkeypatch.setenv("GIBBS_APPELL_CACHE", str(tmp_path))
    messages = []
    first = runtime.compile.library_object(("-O0",), progress=messages.append)      # -O0: the quickest build
    stamp = first.stat().st_mtime_ns
    assert runtime.compile.library_object(("-O0",)) == first and first.stat().st_mtime_ns == stamp   # reused
    assert runtime.compile.library_object(("-O0", "-g0")) != first                                   # per flags
    first.write_bytes(first.read_bytes()[:100])                                                      # truncated
    again = runtime.compile.library_object(("-O0",), progress=messages.append)
    assert again == first and verify_module(again, tmp_path / f"sha256_{again.stem}.txt") is None
    assert any(m.startswith(NOTICE + first.name) for m in messages)
