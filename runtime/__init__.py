"""Runtime: compile generated models with cffi (cached) and drive them from Python."""
from .compile import BuildError, CompilerNotFound, compile_model  # noqa: F401
from .model import CompiledModel, ImpactError, load_model  # noqa: F401
