"""The generator's version, stamped into every generated file (codegen.__version__)."""
__version__ = "0.1.0"
