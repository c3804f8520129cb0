"""sewgen's derivation side: mechanism declarations -> SymPy kinematics -> C kernels (DESIGN.md §2)."""
from .emit import Generated, generate, render_files
from .model import DeclarationError, Mechanism

__all__ = ["DeclarationError", "Generated", "Mechanism", "generate", "render_files"]
