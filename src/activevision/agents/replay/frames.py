"""Frame storage for replay: every camera frame stored once, memory growing with what is kept.

Frames get consecutive integer ids (0, 1, 2, ...) for the life of the buffer. They live in
fixed-size chunks; a chunk is allocated when the first of its frames arrives and recycled once
every frame in it has been released, so a 1,000,000-transition buffer holding 30,000 frames
costs 30,000 frames of memory (rounded up to a chunk).
"""

from __future__ import annotations

import numpy as np


class FrameStore:
    """Append-only, chunked uint8 frame storage addressed by a global frame id.

    Args:
        frame_shape: (H, W) of one frame.
        chunk_frames: frames per allocation chunk.
    """

    def __init__(self, frame_shape: tuple[int, int], chunk_frames: int = 1024) -> None:
        if chunk_frames < 1:
            raise ValueError(f"chunk_frames must be >= 1, got {chunk_frames}")
        self.frame_shape = (int(frame_shape[0]), int(frame_shape[1]))
        self.chunk_frames = int(chunk_frames)
        self._chunks: dict[int, np.ndarray] = {}
        self._spare: list[np.ndarray] = []  # released chunks, reused before allocating
        self.first_id = 0  # oldest frame still kept
        self.next_id = 0  # id the next appended frame gets

    def __len__(self) -> int:
        return self.next_id - self.first_id

    @property
    def allocated_frames(self) -> int:
        """Frames of memory currently allocated (live chunks and spares)."""
        return (len(self._chunks) + len(self._spare)) * self.chunk_frames

    def append(self, frame: np.ndarray) -> int:
        """Store one (H, W) frame and return its id."""
        chunk, offset = divmod(self.next_id, self.chunk_frames)
        if chunk not in self._chunks:
            self._chunks[chunk] = (
                self._spare.pop()
                if self._spare
                else np.empty((self.chunk_frames, *self.frame_shape), dtype=np.uint8)
            )
        self._chunks[chunk][offset] = frame
        self.next_id += 1
        return self.next_id - 1

    def extend(self, frames: np.ndarray) -> int:
        """Store consecutive frames (N, H, W); returns the id of the last one."""
        for frame in frames:
            self.append(frame)
        return self.next_id - 1

    def get(self, ids: np.ndarray) -> np.ndarray:
        """Frames for an array of ids, shape ``ids.shape + (H, W)``."""
        ids = np.asarray(ids, dtype=np.int64)
        flat = ids.ravel()
        if flat.size and (flat.min() < self.first_id or flat.max() >= self.next_id):
            raise IndexError("frame id no longer (or not yet) stored")
        out = np.empty((flat.size, *self.frame_shape), dtype=np.uint8)
        chunks, offsets = np.divmod(flat, self.chunk_frames)
        for i, (chunk, offset) in enumerate(zip(chunks.tolist(), offsets.tolist(), strict=True)):
            out[i] = self._chunks[chunk][offset]
        return out.reshape(*ids.shape, *self.frame_shape)

    def release_before(self, frame_id: int) -> None:
        """Forget all frames with id < ``frame_id``; chunks left empty become spares."""
        self.first_id = max(self.first_id, min(int(frame_id), self.next_id))
        for chunk in [c for c in self._chunks if (c + 1) * self.chunk_frames <= self.first_id]:
            self._spare.append(self._chunks.pop(chunk))
        del self._spare[1:]  # keep one spare chunk at most: memory follows what is stored

    def export(self) -> tuple[int, np.ndarray]:
        """(first id, every kept frame as one contiguous (N, H, W) array)."""
        return self.first_id, self.get(np.arange(self.first_id, self.next_id))

    @classmethod
    def restore(cls, first_id: int, frames: np.ndarray, chunk_frames: int = 1024) -> FrameStore:
        """Rebuild a store from :meth:`export`'s output, keeping the frame ids."""
        store = cls((frames.shape[1], frames.shape[2]), chunk_frames)
        store.first_id = store.next_id = int(first_id)
        store.extend(frames)
        return store
