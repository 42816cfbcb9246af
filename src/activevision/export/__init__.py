"""Export trained head-control policies to ONNX for :mod:`activevision.runtime`.

Needs torch and onnx (``pip install activevision[export]``)::

    from activevision.export import export_run

    export_run("runs/paper", "deploy/policy.onnx")   # writes policy.onnx + policy.json
"""

from activevision.export.onnx_export import (
    DEFAULT_OPSET,
    ExportedPolicy,
    export_onnx,
    policy_metadata,
)
from activevision.export.run import export_run

__all__ = [
    "DEFAULT_OPSET",
    "ExportedPolicy",
    "export_onnx",
    "export_run",
    "policy_metadata",
]
