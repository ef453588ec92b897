"""Where the checkout's parts are, one definition each: its root and the build folder that
`make lib` fills (the C libraries, the bench and budget drivers, the networks' .tnn blobs)."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BUILD_DIR = ROOT / "build"
