"""The scene a command names (--scene) and the horizon of its run (--t-end, else the scene's usual one)."""
from __future__ import annotations

import sys

from codegen.scene import MAX_LINKS, SceneError, default_scene, load_scene

DEFAULT_T_END = {"paper_case1": 1.5, "paper_case2": 1.75, "chain4": 1.5, "arm_obstacle": 3.0,
                 "two_chains": 2.5}   # s; any other: 1.0


def scene_and_horizon(args):
    """The scene named by ``args.scene`` (or the built-in chain of ``args.links`` links, where the command has
    --links) and the run's horizon (``args.t_end``, else the scene's usual one), or None after printing why the
    scene cannot be loaded.  The scene's warnings are printed on loading."""
    links = getattr(args, "links", None)
    try:
        if links is not None and not 1 <= links <= MAX_LINKS:
            raise SceneError(f"--links: must be in 1..{MAX_LINKS}, got {links}")
        scene = default_scene(links) if links is not None else load_scene(args.scene or "paper-case1")
    except SceneError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return None
    for warning in scene.warnings:                # values that suggest a slip of units: said, not refused
        print(f"warning: {warning}", file=sys.stderr)
    return scene, (args.t_end if args.t_end is not None else DEFAULT_T_END.get(scene.name, 1.0))
