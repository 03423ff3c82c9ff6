"""Code generator for the hybrid dynamics of open chains of rigid links (recursive Gibbs-Appell).

    from codegen import generate, load_scene
    from codegen.pipeline import write_model
    model = generate(load_scene("paper-case1"))
    write_model(model, "generated/")          # NAME.h, NAME.c (runtime.compile.copy_library adds the C library)
"""
from .version import __version__  # noqa: E402,F401
from .scene import Scene, SceneError, load_scene, default_scene  # noqa: E402,F401
from .artifact import GeneratedModel  # noqa: E402,F401


def __getattr__(name):
    """``codegen.generate`` is imported on first use: the computer algebra (sympy, jinja2) loads only
    when something is generated, not when a program merely reads scenes or cached models."""
    if name == "generate":
        from .pipeline import generate
        return generate
    raise AttributeError(f"module 'codegen' has no attribute {name!r}")
