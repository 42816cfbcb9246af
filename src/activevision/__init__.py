"""activevision: learn where a humanoid soccer robot should look.

Importing the package is light: it pulls in NumPy-based geometry only (no torch), so the
runtime head controller runs on a robot without PyTorch.
"""

__version__ = "0.1.0"
