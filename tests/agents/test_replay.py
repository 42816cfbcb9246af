import numpy as np
import pytest

from activevision.agents.replay.prioritized import PrioritizedReplayBuffer

SHAPE = (1, 12, 16)


def episode_frames(rng, length, shape=SHAPE):
    return [rng.integers(0, 256, size=shape, dtype=np.uint8) for _ in range(length + 1)]


def fill(buffer, rng, lengths, shape=SHAPE, truncate_last=True):
    """Add episodes of the given lengths; returns the transitions as tuples."""
    added = []
    for length in lengths:
        frames = episode_frames(rng, length, shape)
        for t in range(length):
            last = t == length - 1
            transition = (
                frames[t],
                t % 3,
                float(t),
                frames[t + 1],
                last and not truncate_last,
                last and truncate_last,
            )
            buffer.add(*transition)
            added.append(transition)
    return added


def test_each_frame_is_stored_once():
    buffer = PrioritizedReplayBuffer(100, SHAPE, seed=0, chunk_frames=8)
    fill(buffer, np.random.default_rng(0), [5, 3, 7])
    assert len(buffer) == 15
    assert len(buffer.frames) == 15 + 3  # one frame per step plus one per episode start


def test_large_capacity_does_not_preallocate_frames():
    buffer = PrioritizedReplayBuffer(1_000_000, (1, 120, 160), seed=0, chunk_frames=64)
    assert buffer.frames.allocated_frames == 0
    fill(buffer, np.random.default_rng(0), [10], shape=(1, 120, 160))
    assert buffer.frames.allocated_frames == 64


def test_samples_return_exactly_what_was_stored():
    buffer = PrioritizedReplayBuffer(1000, SHAPE, seed=1, chunk_frames=4)
    added = fill(buffer, np.random.default_rng(1), [4, 6, 1, 5], truncate_last=False)
    batch = buffer.sample(64, beta=0.4)
    for i, slot in enumerate(batch.indices):
        obs, action, reward, next_obs, terminated, _ = added[slot]
        np.testing.assert_array_equal(batch.obs[i], obs)
        np.testing.assert_array_equal(batch.next_obs[i], next_obs)
        assert batch.actions[i] == action and batch.rewards[i] == reward
        assert batch.terminated[i] == float(terminated)
    assert batch.obs.dtype == np.uint8 and batch.obs.shape == (64, *SHAPE)


def test_frame_stacks_are_exact_and_not_duplicated():
    stack, rng = 3, np.random.default_rng(2)
    buffer = PrioritizedReplayBuffer(1000, (stack, 4, 5), seed=2, chunk_frames=5)
    added = []
    for length in (6, 4):
        frames = [rng.integers(0, 256, (4, 5), dtype=np.uint8) for _ in range(length + 1)]
        history = [frames[0]] * (stack - 1) + frames  # "repeat the reset frame" padding
        observations = [np.stack(history[t : t + stack]) for t in range(length + 1)]
        for t in range(length):
            transition = (observations[t], 0, 0.0, observations[t + 1], False, t == length - 1)
            buffer.add(*transition)
            added.append(transition)
    assert len(buffer.frames) == 10 + 2 * stack  # a new episode stores its whole first stack
    batch = buffer.sample(32, beta=1.0)
    for i, slot in enumerate(batch.indices):
        np.testing.assert_array_equal(batch.obs[i], added[slot][0])
        np.testing.assert_array_equal(batch.next_obs[i], added[slot][3])


def test_wraparound_frees_old_frames_and_stays_exact():
    buffer = PrioritizedReplayBuffer(10, SHAPE, seed=3, chunk_frames=4)
    added = fill(buffer, np.random.default_rng(3), [7] * 10)
    assert len(buffer) == 10
    assert buffer.frames.allocated_frames <= 10 + 2 + 2 * 4  # live frames + partial chunks
    live = added[-10:]
    batch = buffer.sample(16, beta=0.4)
    for i, slot in enumerate(batch.indices):
        age = (slot - buffer.cursor) % 10  # 0 = oldest live transition
        np.testing.assert_array_equal(batch.obs[i], live[age][0])
        np.testing.assert_array_equal(batch.next_obs[i], live[age][3])


def test_priorities_new_at_max_and_updated_from_td_errors():
    buffer = PrioritizedReplayBuffer(10, SHAPE, alpha=0.5, eps=1e-6, seed=4)
    fill(buffer, np.random.default_rng(4), [3])
    np.testing.assert_allclose(buffer.tree.leaves(3), 1.0)
    buffer.update_priorities(np.array([0, 1]), np.array([-3.0, 0.0]))
    np.testing.assert_allclose(buffer.tree.leaves(3), [np.sqrt(3.0 + 1e-6), np.sqrt(1e-6), 1.0])
    fill(buffer, np.random.default_rng(5), [1])
    assert buffer.tree.get(np.array([3]))[0] == pytest.approx(np.sqrt(3.0 + 1e-6))
    batch = buffer.sample(4, beta=0.4)
    assert batch.weights.max() == pytest.approx(1.0) and np.all(batch.weights > 0)


def test_state_dict_round_trip_is_exact():
    buffer = PrioritizedReplayBuffer(20, SHAPE, seed=6, chunk_frames=4)
    rng = np.random.default_rng(6)
    fill(buffer, rng, [9, 9, 9])  # wraps around
    buffer.update_priorities(np.array([1, 5]), np.array([2.0, 0.1]))
    state = buffer.state_dict()
    assert all(isinstance(v, np.ndarray) and v.dtype != object for v in state.values())
    restored = PrioritizedReplayBuffer.from_state_dict(state)
    for a, b in zip(buffer.sample(8, 0.5), restored.sample(8, 0.5), strict=True):
        np.testing.assert_array_equal(a, b)
    more = episode_frames(np.random.default_rng(7), 2)
    for b in (buffer, restored):
        b.add(more[0], 1, 1.0, more[1], False, False)
    np.testing.assert_array_equal(buffer.tree.leaves(), restored.tree.leaves())
    assert len(buffer.frames) == len(restored.frames)


def test_rejects_wrong_observations():
    buffer = PrioritizedReplayBuffer(10, SHAPE)
    with pytest.raises(ValueError):
        buffer.add(np.zeros(SHAPE, np.float32), 0, 0.0, np.zeros(SHAPE, np.uint8), False, False)
    with pytest.raises(ValueError):
        buffer.sample(4, 0.4)


def reference_n_step(added, live, j, n, gamma):
    """Straight loop: discounted rewards from transition j along its episode, at most n."""
    total, k = 0.0, 0
    while True:
        _, _, reward, next_obs, terminated, truncated = added[j + k]
        total += gamma**k * reward
        k += 1
        if terminated or truncated or k == n or j + k == live.stop:
            return total, next_obs, terminated, gamma**k


@pytest.mark.parametrize(
    ("capacity", "n"),
    [(1000, 3), (1000, 1), (20, 4)],  # 20: the buffer has wrapped around
)
def test_n_step_returns_follow_episodes_to_their_ends(capacity, n):
    gamma = 0.9
    buffer = PrioritizedReplayBuffer(capacity, SHAPE, seed=8, n_step=n, gamma=gamma)
    rng = np.random.default_rng(8)
    added = fill(buffer, rng, [5, 2], truncate_last=True)  # truncated episodes
    added += fill(buffer, rng, [4, 1, 6], truncate_last=False)  # terminated episodes
    frames = episode_frames(rng, 3)  # an episode still running
    for t in range(3):
        added.append((frames[t], 2, 10.0 + t, frames[t + 1], False, False))
        buffer.add(*added[-1])
    live = range(max(0, len(added) - capacity), len(added))

    batch = buffer.sample(256, beta=0.4)
    assert set(batch.indices.tolist()) == {j % capacity for j in live}  # every slot checked
    for i, slot in enumerate(batch.indices):
        j = next(j for j in live if j % capacity == slot)
        reward, next_obs, terminated, discount = reference_n_step(added, live, j, n, gamma)
        np.testing.assert_array_equal(batch.obs[i], added[j][0])
        assert batch.actions[i] == added[j][1]
        assert batch.rewards[i] == pytest.approx(reward, rel=1e-6)
        np.testing.assert_array_equal(batch.next_obs[i], next_obs)
        assert batch.terminated[i] == float(terminated)
        assert batch.discounts[i] == pytest.approx(discount, rel=1e-6)


def test_n_step_hand_computed_case():
    buffer = PrioritizedReplayBuffer(10, SHAPE, seed=9, n_step=3, gamma=0.5)
    frames = episode_frames(np.random.default_rng(9), 4)
    for t, reward in enumerate([1.0, -1.0, 2.0, 4.0]):
        buffer.add(frames[t], 0, reward, frames[t + 1], t == 3, False)
    batch = buffer.sample(64, beta=1.0)
    by_slot = {int(s): i for i, s in enumerate(batch.indices)}
    expected = {  # slot: (reward sum, discount, terminal, index of next frame)
        0: (1 - 0.5 + 0.25 * 2, 0.125, 0.0, 3),
        1: (-1 + 0.5 * 2 + 0.25 * 4, 0.125, 1.0, 4),
        2: (2 + 0.5 * 4, 0.25, 1.0, 4),
        3: (4.0, 0.5, 1.0, 4),
    }
    for slot, (reward, discount, terminal, frame) in expected.items():
        i = by_slot[slot]
        assert batch.rewards[i] == pytest.approx(reward)
        assert batch.discounts[i] == pytest.approx(discount)
        assert batch.terminated[i] == terminal
        np.testing.assert_array_equal(batch.next_obs[i], frames[frame])


def test_auxiliary_targets_travel_with_their_transitions():
    buffer = PrioritizedReplayBuffer(8, SHAPE, seed=10, aux_dim=2)
    frames = episode_frames(np.random.default_rng(10), 12)
    for t in range(12):  # wraps around: slots hold steps 4..11
        buffer.add(frames[t], 0, 0.0, frames[t + 1], False, False, aux=np.array([t, -t]))
    batch = buffer.sample(32, beta=1.0)
    for i, slot in enumerate(batch.indices):
        step = slot + 8 if slot < 4 else slot
        np.testing.assert_array_equal(batch.obs[i], frames[step])
        np.testing.assert_array_equal(batch.aux[i], [step, -step])
    restored = PrioritizedReplayBuffer.from_state_dict(buffer.state_dict())
    np.testing.assert_array_equal(restored.sample(32, 1.0).aux, buffer.sample(32, 1.0).aux)
    with pytest.raises(ValueError, match="aux"):
        buffer.add(frames[0], 0, 0.0, frames[1], False, False)  # aux missing
