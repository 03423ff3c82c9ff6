"""The error every check of a scene raises (a scene file, a URDF chain, a parameter vector): below codegen.scene
and codegen.urdf, so that both raise it and the scene loader reads URDF without an import circle."""


class SceneError(ValueError):
    """A scene field has a bad value; the message names the field and the allowed range."""
