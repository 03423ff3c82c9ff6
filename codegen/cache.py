"""The on-disk cache shared by ``python -m codegen`` and ``runtime.load_model``.

The cache directory is ``$GIBBS_APPELL_CACHE``, else ``$XDG_CACHE_HOME/gibbs-appell-chains``, else
``~/.cache/gibbs-appell-chains``.  It holds two kinds of entries:

* ``gen_KEY.json`` -- the generated text of one model (name, header, source, cdef and the operation
  counts of its functions), keyed by the scene hash, the model name, ``bake_params``, ``specialise``
  and the generator fingerprint.  The file carries the sha256 of its payload and is checked on load.
* ``_gac_KEY.<ext>`` with ``sha256_gac_KEY.txt`` -- a compiled cffi module (written by
  ``runtime.compile``) and its sidecar in ``sha256sum`` format, checked before the module is imported.
* ``gac_lib_KEY.o`` with ``sha256_gac_lib_KEY.txt`` -- the C library compiled once (``runtime.compile.library_object``),
  linked into every module built with the same library text and flags.

An entry that fails its check (unreadable, malformed, missing its hash, hash mismatch) is corrupted:
one line ``cache: rebuilding corrupted entry FILE (REASON)`` is reported and the entry is rebuilt.
Entries are written to a temporary file and moved into place, and each entry is built under an
exclusive lock (hidden ``.lock_*`` files), so concurrent processes building one model all succeed.
"""
from __future__ import annotations

import functools
import hashlib
import importlib.util
import json
import os
import shutil
import sys
import tempfile
from contextlib import contextmanager
from pathlib import Path

from . import interface
from .artifact import GeneratedModel, OpCount, RenderedFunction, scene_hash, text_digest
from .options import BuildOptions, build_options
from .scene import Scene
from .specialise import layout_for

try:
    import fcntl
except ImportError:  # pragma: no cover - not POSIX: no cross-process lock
    fcntl = None

GEN_FORMAT = 2
GEN_PAYLOAD_KEYS = ("name", "header", "source", "cdef", "functions")
TEXT_KEYS = ("header", "source", "cdef")
FUNCTION_KEYS = ("name", "summary", "inputs", "output", "output_size", "ops")
OPS_FIELDS = ("add", "mul", "div", "sqrt", "trig", "other_calls")
FIX = "set GIBBS_APPELL_CACHE to a writable directory"


class CacheError(RuntimeError):
    """The cache directory cannot be used; the message names it, says why and what to do."""


# ---------------------------------------------------------------------------
# the directory
# ---------------------------------------------------------------------------
def cache_dir() -> Path:
    """The cache directory, created if missing; CacheError if it cannot be created or written."""
    if os.environ.get("GIBBS_APPELL_CACHE"):
        base, origin = Path(os.environ["GIBBS_APPELL_CACHE"]).expanduser(), "GIBBS_APPELL_CACHE"
    else:
        base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "gibbs-appell-chains"
        origin = "the default location"
    where = f"cache directory {str(base)!r} (from {origin})"
    if base.exists() and not base.is_dir():
        raise CacheError(f"{where} is not a directory; {FIX}")
    try:
        base.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        blocker = next((parent for parent in base.absolute().parents if parent.exists()), None)
        why = f"{blocker} is a file, not a directory" if blocker and not blocker.is_dir() else exc.strerror or exc
        raise CacheError(f"{where} cannot be created ({why}); {FIX}") from None
    if base not in _WRITABLE:
        try:
            handle, probe = tempfile.mkstemp(prefix=".probe-", dir=base)
            os.close(handle)
            os.unlink(probe)
        except OSError as exc:
            raise CacheError(f"{where} is not writable ({exc.strerror or exc}); {FIX}") from None
        _WRITABLE.add(base)
    return base


_WRITABLE: set[Path] = set()     # directories found writable in this process


@contextmanager
def entry_lock(folder: Path, entry: str):
    """Hold an exclusive cross-process lock on one cache entry while it is checked or built."""
    if fcntl is None:  # pragma: no cover
        yield
        return
    with open(folder / f".lock_{entry}", "a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def clear_entry(path: Path) -> None:
    """Remove whatever stands where the cache entry ``path`` (a file) belongs but is no regular file (a
    directory, a dangling link, a socket), so that the entry can be written there again."""
    if path.is_symlink() or (path.exists() and not path.is_file()):
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path)
        else:
            path.unlink()


def write_atomic(path: Path, data: bytes) -> None:
    """Write ``data`` to a temporary file beside ``path`` and rename it into place."""
    clear_entry(path)
    handle, tmp = tempfile.mkstemp(prefix=f".{path.name}-", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(handle, "wb") as out:
            out.write(data)
        os.chmod(tmp, 0o644)                 # mkstemp makes the file private to its owner
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def report_corrupted(filename: str, reason: str, progress=None) -> None:
    """The one-line notice for a corrupted entry: to ``progress`` if given, else to stderr."""
    message = f"cache: rebuilding corrupted entry {filename} ({reason})"
    if progress:
        progress(message)
    else:
        print(message, file=sys.stderr, flush=True)


def sha256_of(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


# ---------------------------------------------------------------------------
# the generated text
# ---------------------------------------------------------------------------
def _hash_generator_sources() -> str:
    digest = hashlib.sha256()
    for package, pattern in (("codegen", "*.py"), ("templates", "*.j2")):
        folder = next(iter(importlib.util.find_spec(package).submodule_search_locations))   # not imported
        for path in sorted(Path(folder).glob(pattern)):
            digest.update(path.name.encode())
            digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


@functools.cache
def generator_fingerprint() -> str:
    """Hash of the generator's code and templates (computed once per process), so cached text
    never outlives a change of the generator."""
    return _hash_generator_sources()


def generation_key(scene: Scene, options: BuildOptions | None = None, name: str | None = None) -> str:
    """The generated text's key: the scene, the model's name, the options that shape the text and the generator."""
    options = build_options(scene) if options is None else options
    text = f"{scene_hash(scene)}|{name or scene.name}|{options.generation_text()}|{generator_fingerprint()}"
    return hashlib.sha256(text.encode()).hexdigest()[:20]


def _payload(model: GeneratedModel) -> dict:
    functions = [{"name": f.name, "summary": f.summary, "inputs": list(f.inputs), "output": f.output,
                  "output_size": f.output_size, "ops": [getattr(f.ops, k) for k in OPS_FIELDS]}
                 for f in model.functions]
    return {"name": model.name, "header": model.header, "source": model.source, "cdef": model.cdef,
            "functions": functions}


def _payload_hash(payload: dict, texts: str) -> str:
    """sha256 over the payload's fields in a fixed order: the three texts through their text_digest ``texts`` (no
    re-serialising of megabytes of C on every load, and no second pass over them for the module's key), the
    small fields as canonical JSON."""
    digest = hashlib.sha256()
    for field in GEN_PAYLOAD_KEYS:
        value = payload.get(field)
        if field in TEXT_KEYS:
            continue
        digest.update(field.encode())
        digest.update(b"\0")
        digest.update((value if isinstance(value, str) else json.dumps(value, sort_keys=True,
                                                                       separators=(",", ":"))).encode())
        digest.update(b"\0")
    digest.update(b"texts\0" + texts.encode())
    return digest.hexdigest()


def _read_generated(path: Path, key: str, name: str) -> tuple[dict | None, str | None]:
    """(payload, None) for a good entry, (None, reason) for a corrupted one, (None, None) if absent."""
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        return None, None
    except OSError as exc:
        return None, f"unreadable: {exc.strerror or exc}"
    try:
        data = json.loads(raw)
    except ValueError:                     # JSONDecodeError or UnicodeDecodeError
        return None, "not valid JSON"
    if not isinstance(data, dict):
        return None, "not a JSON object"
    for field in ("format", "key", "sha256", "payload"):
        if field not in data:
            return None, f"missing key {field!r}"
    if data["format"] != GEN_FORMAT or data["key"] != key:
        return None, "format or key does not match"
    payload = data["payload"]
    if not isinstance(payload, dict):
        return None, "payload is not a JSON object"
    for field in GEN_PAYLOAD_KEYS:
        if field not in payload:
            return None, f"missing key {field!r}"
    if not all(isinstance(payload[k], str) for k in TEXT_KEYS):
        return None, "payload does not match its key"
    payload["digest"] = text_digest(*(payload[k] for k in TEXT_KEYS))
    if _payload_hash(payload, payload["digest"]) != data["sha256"]:
        return None, "sha256 mismatch"
    if payload["name"] != name:
        return None, "payload does not match its key"
    functions = payload["functions"]
    if not isinstance(functions, list) or not all(
            isinstance(f, dict) and all(k in f for k in FUNCTION_KEYS) and isinstance(f["ops"], list)
            and len(f["ops"]) == len(OPS_FIELDS)
            for f in functions):
        return None, "malformed function list"
    return payload, None


def _model_from_payload(payload: dict, scene: Scene, options: BuildOptions) -> GeneratedModel:
    functions = [RenderedFunction(f["name"], f["summary"], tuple(f["inputs"]), f["output"], f["output_size"],
                                  [], OpCount(*f["ops"])) for f in payload["functions"]]
    return GeneratedModel(payload["name"], payload["header"], payload["source"], payload["cdef"], functions,
                          options, layout_for(scene, options.specialise), payload["digest"])   # (digest: computed
                                                                                     # when the entry was checked)


def generate_cached(scene: Scene, options: BuildOptions | None = None, *, name: str | None = None,
                    progress=None, refresh: bool = False) -> GeneratedModel:
    """``codegen.generate`` through the on-disk cache of generated text (``options``: codegen.options.build_options;
    None: the scene's defaults).

    A cached model has everything but the C lines of its functions (``functions[i].lines`` is
    empty; the text is in ``.source``) and its stage timings.  ``refresh`` always runs the generator
    and stores the result (the command line does this, so it reports its own timings).
    """
    options = build_options(scene) if options is None else options
    name = name or scene.name
    key = generation_key(scene, options, name)
    folder = cache_dir()
    path = folder / f"gen_{key}.json"
    with entry_lock(folder, path.stem):
        if not refresh:
            payload, problem = _read_generated(path, key, name)
            if payload is not None:
                return _model_from_payload(payload, scene, options)
            if problem:
                report_corrupted(path.name, problem, progress)
        from .pipeline import generate          # the computer algebra loads only when a model is generated
        model = generate(scene, options, name=name, progress=progress or (lambda m: None))
        if _hash_generator_sources() == generator_fingerprint():   # the generator did not change meanwhile
            payload = _payload(model)
            data = {"format": GEN_FORMAT, "key": key, "sha256": _payload_hash(payload, model.text_digest()),
                    "payload": payload}
            write_atomic(path, json.dumps(data).encode())
    return model
