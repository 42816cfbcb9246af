"""The policy shipped inside the package (``activevision/pretrained/policy.onnx``)."""

from __future__ import annotations

from pathlib import Path

from activevision.runtime.metadata import METADATA_FILENAME, MODEL_FILENAME, PolicyFileError

#: Folder of the shipped policy inside the installed package.
PRETRAINED_DIR = Path(__file__).resolve().parent.parent / "pretrained"


def pretrained_policy_path() -> Path:
    """Path of the shipped ``policy.onnx`` (its ``policy.json`` lies beside it).

    Raises:
        PolicyFileError: the package was built without the pretrained policy (or only half
            of it); export one with ``activevision export RUN_DIR`` and pass its path instead.
    """
    model = PRETRAINED_DIR / MODEL_FILENAME
    metadata = PRETRAINED_DIR / METADATA_FILENAME
    missing = [p.name for p in (model, metadata) if not p.is_file()]
    if missing:
        raise PolicyFileError(
            f"no pretrained policy in this installation ({', '.join(missing)} missing in "
            f"{PRETRAINED_DIR}); export a trained run with `activevision export RUN_DIR` and "
            "load that policy.onnx instead"
        )
    return model
