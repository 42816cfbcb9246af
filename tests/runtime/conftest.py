"""Shared fixtures of the runtime tests: a small exported policy and real camera frames."""

from __future__ import annotations

import functools
import json
import math
from collections.abc import Callable, Iterator
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("onnx")
pytest.importorskip("onnxruntime")

from activevision.agents.q_network import QNetwork  # noqa: E402
from activevision.export import ExportedPolicy, export_onnx, policy_metadata  # noqa: E402
from activevision.geometry import CameraConfig  # noqa: E402

#: (width, height) of the camera frames the tests feed the controller.
FRAME_SIZES = ((160, 120), (640, 480), (320, 240), (333, 250))
LUMA = np.array([0.299, 0.587, 0.114])


def eight_way_table(step_deg: float = 3.0) -> np.ndarray:
    """The 9-action table of activevision.envs.actions (written out: envs imports gymnasium)."""
    s = math.radians(step_deg)
    d = s * math.sqrt(2) / 2
    moves = [(0, 0), (s, 0), (-s, 0), (0, -s), (0, s), (d, -d), (d, d), (-d, -d), (-d, d)]
    return np.asarray(moves, dtype=np.float64)


def make_network(stack: int = 1, seed: int = 0, dueling: bool = False) -> QNetwork:
    torch.manual_seed(seed)
    return QNetwork(9, stack=stack, dueling=dueling).eval()


def export(network: QNetwork, directory: Path, **options) -> ExportedPolicy:
    metadata = policy_metadata(eight_way_table(), CameraConfig())
    return export_onnx(network, directory / "policy.onnx", metadata, **options)


def render_frames(width: int, height: int, count: int) -> np.ndarray:
    """``count`` real (count, height, width) uint8 camera frames from the package's renderer,
    or structured synthetic frames (lines and a ball on a gradient) when it cannot be used."""
    rng = np.random.default_rng(width * 1000 + height)
    try:
        import numba

        from activevision.rendering import Renderer

        renderer = Renderer(camera=CameraConfig(width=width, height=height))
        pose = np.column_stack(
            [
                rng.uniform(-3, 3, count),
                rng.uniform(-2, 2, count),
                rng.uniform(-math.pi, math.pi, count),
            ]
        )
        pan = rng.uniform(-1.2, 1.2, count)
        tilt = rng.uniform(0.15, 1.0, count)
        ball = pose[:, :2] + rng.uniform(-2, 2, (count, 2))
        # One numba thread: the OpenMP workers of a parallel render spin for a while after it
        # and starve torch and onnxruntime on a small machine (80 ms per forward on 2 cores).
        threads = numba.get_num_threads()
        numba.set_num_threads(1)
        try:
            return renderer.render(pose, pan, tilt, ball)
        finally:
            numba.set_num_threads(threads)
    except Exception:  # renderer unavailable: synthetic but structured frames
        y, x = np.mgrid[0:height, 0:width]
        frames = []
        for _ in range(count):
            a, b, c = rng.uniform(-1, 1, 3)
            img = 60 + 40 * (y / height) + 5 * rng.standard_normal((height, width))
            img[np.abs(a * x + b * y + c * width) < 0.02 * width] = 230
            cx, cy, r = rng.uniform(0, width), rng.uniform(0, height), rng.uniform(5, 30)
            img[(x - cx) ** 2 + (y - cy) ** 2 < r * r] = 250
            frames.append(np.clip(img, 0, 255).astype(np.uint8))
        return np.stack(frames)


def colourise(grey: np.ndarray, seed: int = 0) -> np.ndarray:
    """An (H, W, 3) RGB frame whose channels differ (a tinted, noisy version of ``grey``)."""
    rng = np.random.default_rng(seed)
    g = grey.astype(np.float64)
    rgb = np.stack([0.7 * g + 60, g, 0.5 * g + 40 * rng.random(g.shape)], axis=-1)
    return np.clip(np.rint(rgb), 0, 255).astype(np.uint8)


@functools.cache
def area_matrix(n_in: int, n_out: int) -> np.ndarray:
    """Dense (n_out, n_in) exact area-averaging matrix, float64 (the test's reference)."""
    scale = n_in / n_out
    matrix = np.zeros((n_out, n_in))
    for i in range(n_out):
        lo, hi = i * scale, (i + 1) * scale
        for j in range(math.floor(lo), min(math.ceil(hi), n_in)):
            matrix[i, j] = max(0.0, min(j + 1, hi) - max(j, lo)) / scale
    return matrix


def apply_along_rows(matrix: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``matrix @ x`` using only each row's nonzero taps (plain NumPy, no BLAS threads)."""
    out = np.empty((matrix.shape[0], x.shape[1]))
    for i, row in enumerate(matrix):
        taps = np.flatnonzero(row)
        out[i] = (row[taps, None] * x[taps]).sum(axis=0)
    return out


def reference_preprocess(frame: np.ndarray, color_order: str = "rgb") -> np.ndarray:
    """Slow float64 reference: BT.601 grey, exact area average to 160 x 120, round half up."""
    if frame.ndim == 3 and frame.shape[2] == 3:
        weights = LUMA if color_order == "rgb" else LUMA[::-1]
        grey = (frame.astype(np.float64) * weights).sum(axis=2)
    else:
        grey = frame.reshape(frame.shape[0], frame.shape[1]).astype(np.float64)
    rows = apply_along_rows(area_matrix(grey.shape[0], 120), grey)
    small = apply_along_rows(area_matrix(grey.shape[1], 160), rows.T).T
    return np.clip(np.floor(small + 0.5), 0, 255).astype(np.uint8)


@pytest.fixture(scope="module", autouse=True)
def one_torch_thread() -> Iterator[None]:
    """Batch-1 inference is fastest on one thread, and immune to other jobs on the machine."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)


@pytest.fixture(scope="session")
def policy(tmp_path_factory) -> SimpleNamespace:
    """A freshly initialised paper network and its export (stack 1)."""
    network = make_network()
    paths = export(network, tmp_path_factory.mktemp("policy"))
    return SimpleNamespace(
        network=network, model_path=paths.model_path, metadata_path=paths.metadata_path
    )


@pytest.fixture(scope="session")
def frames() -> Callable[[int, int], np.ndarray]:
    """frames(width, height) -> (4, height, width) real camera frames (cached)."""
    cache: dict[tuple[int, int], np.ndarray] = {}

    def get(width: int, height: int) -> np.ndarray:
        if (width, height) not in cache:
            cache[(width, height)] = render_frames(width, height, 4)
        return cache[(width, height)]

    return get


def assert_record_rejected(model: Path, key: str, record: object, message: str) -> None:
    """policy.json's ``key`` replaced by ``record``: loading it, alone or through a
    HeadController, is one PolicyFileError matching ``message`` and naming the file."""
    from activevision.runtime import HeadController, PolicyFileError, load_metadata

    path = model.with_suffix(".json")
    values = json.loads(path.read_text())
    values[key] = record
    path.write_text(json.dumps(values))
    with pytest.raises(PolicyFileError, match=message) as error:
        load_metadata(path)
    assert str(path) in str(error.value)  # names the file
    with pytest.raises(PolicyFileError, match=message):
        HeadController(model)


@pytest.fixture(scope="session")
def helpers() -> SimpleNamespace:
    """The reference functions above, for test modules (importlib mode has no conftest
    imports)."""
    return SimpleNamespace(
        eight_way_table=eight_way_table,
        make_network=make_network,
        export=export,
        colourise=colourise,
        area_matrix=area_matrix,
        reference_preprocess=reference_preprocess,
        frame_sizes=FRAME_SIZES,
        assert_record_rejected=assert_record_rejected,
    )
