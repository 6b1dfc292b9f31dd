"""Shared pytest fixtures. tests/ is a plain folder (no __init__.py): dartpy installs a
top-level package named ``tests``."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
# ../shared/data beside the repository; VISPRIM_SHARED_DATA overrides it (git worktrees).
SHARED_DATA = Path(os.environ.get("VISPRIM_SHARED_DATA", REPO.parent / "shared" / "data"))


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """The real recordings in ../shared/data (read in place, never copied)."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"real recordings not found at {SHARED_DATA}")
    return SHARED_DATA
