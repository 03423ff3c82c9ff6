"""Where a command will write: checked before any work, so that a bad path costs nothing and leaves nothing.

Each check returns '' when the path can be written, else one sentence naming the option, the path and why.
"""
from __future__ import annotations

import os
from pathlib import Path


def _existing_ancestor(path: Path) -> Path:
    for parent in path.absolute().parents:
        if parent.exists():
            return parent
    return Path("/")


def output_file_problem(option: str, value: str) -> str:
    """A file the command will create or overwrite: its folder must exist and be writable."""
    path = Path(value)
    if path.is_dir():
        return f"{option}: {value} is a directory; give a file name"
    folder = path.absolute().parent
    if not folder.exists():
        blocker = _existing_ancestor(path)
        if not blocker.is_dir():
            return f"{option}: cannot write {value}: {blocker} is a file, not a directory"
        return f"{option}: cannot write {value}: the directory {folder} does not exist (create it first)"
    if not folder.is_dir():
        return f"{option}: cannot write {value}: {folder} is a file, not a directory"
    if path.exists() and not os.access(path, os.W_OK):
        return f"{option}: cannot write {value}: permission denied"
    if not path.exists() and not os.access(folder, os.W_OK | os.X_OK):
        return f"{option}: cannot write {value}: the directory {folder} is not writable"
    return ""


def output_dir_problem(option: str, value: str) -> str:
    """A directory the command will create (with its parents) and write files into."""
    if not value.strip():
        return f"{option}: empty; give a directory"
    path = Path(value)
    if not path.exists() and os.path.lexists(path):
        return f"{option}: {value} is a broken symbolic link"
    if path.exists():
        if not path.is_dir():
            return f"{option}: {value} exists and is not a directory"
        if not os.access(path, os.W_OK | os.X_OK):
            return f"{option}: the directory {value} is not writable"
        return ""
    blocker = _existing_ancestor(path)
    if not blocker.is_dir():
        return f"{option}: cannot create {value}: {blocker} is a file, not a directory"
    if not os.access(blocker, os.W_OK | os.X_OK):
        return f"{option}: cannot create {value}: the directory {blocker} is not writable"
    return ""
