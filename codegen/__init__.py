"""Code generator for the hybrid dynamics of open chains of rigid links (recursive Gibbs-Appell).

    from codegen import generate, load_scene
    model = generate(load_scene("paper-case1"))
    model.write("generated/")
"""
__version__ = "0.1.0"

from .scene import Scene, SceneError, load_scene, default_scene  # noqa: E402,F401
from .pipeline import generate, GeneratedModel  # noqa: E402,F401
