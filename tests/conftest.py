"""Shared by every test."""

import pytest


@pytest.fixture(autouse=True)
def _sb3_logs_in_tmp_path(tmp_path_factory, monkeypatch):
    """Stable-Baselines3 used outside the package's trainers (as a user would) logs to a
    new ``SB3-<time>`` folder in the temporary directory at every ``learn``: give it a
    folder of the test session's instead, so the tests leave none behind."""
    monkeypatch.setenv("SB3_LOGDIR", str(tmp_path_factory.getbasetemp() / "sb3"))
