"""What the generator hands on, in plain data: the C text of one model with its functions' summaries and
operation counts, and the scene hash that keys it.  Light on purpose (no sympy, no jinja2): the runtime
reads cached models through it without loading the computer algebra."""
from __future__ import annotations

import functools
import hashlib
import json
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .options import BuildOptions
    from .scene import Scene
    from .specialise import Layout


@dataclass(frozen=True)
class OpCount:
    add: int = 0
    mul: int = 0
    div: int = 0
    sqrt: int = 0
    trig: int = 0
    other_calls: int = 0

    @property
    def calls(self) -> int:
        return self.sqrt + self.trig + self.other_calls

    @property
    def total(self) -> int:
        return self.add + self.mul + self.div + self.calls

    def __add__(self, other: "OpCount") -> "OpCount":
        return OpCount(*(a + b for a, b in zip(self.as_tuple(), other.as_tuple())))

    def as_tuple(self):
        return (self.add, self.mul, self.div, self.sqrt, self.trig, self.other_calls)

    def as_dict(self) -> dict:
        return {"add": self.add, "mul": self.mul, "div": self.div, "calls": self.calls, "total": self.total}

    def __str__(self) -> str:
        return f"{self.total} ops ({self.add} add, {self.mul} mul, {self.div} div, {self.calls} calls)"


@dataclass
class RenderedFunction:
    """What the templates need of one kernel."""

    name: str
    summary: str
    inputs: tuple[str, ...]
    output: str
    output_size: int
    lines: list[str]
    ops: OpCount
    parts: list = None               # a long function split: lines of each part (values crossing parts in s[])
    scratch: int = 0                 # doubles of s[] a split function needs
    out_type: str = "double"         # the C type of the output's elements ("long double": interface.EXTENDED_KERNELS)


@dataclass(frozen=True)
class GeneratedModel:
    """The generated files of one scene, as text, with what made them."""

    name: str
    header: str
    source: str
    cdef: str
    functions: list[RenderedFunction]
    options: BuildOptions             # every choice the model was generated with (codegen.options)
    layout: Layout                    # its coordinates, contacts and Jacobian rows (codegen.specialise)
    digest: str                       # text_digest(header, source, cdef): the compiled module's key builds on it
    timings: dict = field(default_factory=dict)   # seconds per stage (derive, cse, render, ...); {} when cached

    @property
    def bake_params(self) -> bool:
        """The parameters are constants in the code (p is ignored)."""
        return self.options.bake_params

    def text_digest(self) -> str:
        return self.digest


def text_digest(header: str, source: str, cdef: str) -> str:
    """sha256 of a model's three texts, computed once per load: the cached text's check and the compiled module's
    key both build on it."""
    digest = hashlib.sha256()
    for text in (header, source, cdef):
        digest.update(text.encode())
        digest.update(b"\0")
    return digest.hexdigest()


def scene_hash(scene: Scene) -> str:
    """sha256 of a canonical JSON form of the scene (every field, floats by repr); remembered per scene (a
    frozen, hashable value) so that loading a long chain's model again does not walk it again."""
    return _scene_hash(scene)


@functools.lru_cache(maxsize=256)
def _scene_hash(scene: Scene) -> str:
    text = json.dumps(_canonical(scene), sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def _canonical(value):
    """The scene's fields as JSON data: floats by repr, dataclasses as {"type": name, field: value}.  Equal parts
    (a chain's identical links, joints and twists) are converted once."""
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, (tuple, list)) or hasattr(value, "__dataclass_fields__"):
        try:
            return _canonical_part(value)
        except TypeError:                   # unhashable: a list, or a tuple holding one
            return _convert(value)
    return value


@functools.lru_cache(maxsize=4096)
def _canonical_part(value):
    return _convert(value)


def _convert(value):
    if isinstance(value, (list, tuple)):
        return [_canonical(v) for v in value]
    return {"type": type(value).__name__, **{k: _canonical(getattr(value, k)) for k in value.__dataclass_fields__
                                             if not _unchanged_default(value, k)}}


def _unchanged_default(value, field: str) -> bool:
    """A field added later whose default keeps every earlier scene's meaning (a scene's free base, a link's radius 0)
    is left out of the canonical form, so that those scenes keep their hashes (and their generated text and compiled
    modules)."""
    if field == "radius":                   # a link's capsule radius: 0 is the segment every earlier scene had
        return type(value).__name__ in ("LineLink", "RigidLink") and value.radius == 0.0
    if field == "link_restitution":         # the e of capsule links meeting: unset in every earlier scene
        return type(value).__name__ == "Scene" and value.link_restitution is None
    if field == "gravity_direction":        # gravity along -X2, as in every earlier scene
        return type(value).__name__ == "Scene" and value.gravity_direction == (0.0, -1.0, 0.0)
    if field == "contact_pairs":            # which link pairs are contacts: every possible one in earlier scenes
        return type(value).__name__ == "Scene" and value.contact_pairs is None
    if field in ("obstacles", "obstacle_restitution"):   # fixed obstacles (and their default e): none earlier
        return type(value).__name__ == "Scene" and not value.obstacles
    if field == "link_friction":            # capsule links meeting without friction, as in every earlier scene
        return type(value).__name__ in ("Scene", "Chains") and value.link_friction == 0.0
    if field == "friction" and type(value).__name__ == "Obstacle":   # a frictionless obstacle, as every earlier one
        return value.friction == 0.0
    if field in ("half_extents", "rotation", "normal"):  # a box's and a plane's: unset on spheres and bars
        return type(value).__name__ == "Obstacle" and getattr(value, field) is None
    return field == "base" and type(value).__name__ == "Scene" and value.base.kind == "free"

