"""Runtime: compile generated models with cffi (cached) and drive the hybrid loop from Python."""
from .compile import BuildError, CacheError, CompilerNotFound, compile_model  # noqa: F401
from .model import CompiledModel, ImpactError, load_model  # noqa: F401
from .simulate import Contact, Impact, SimulationResult, simulate  # noqa: F401
