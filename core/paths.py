"""Where the shipped scenes and shaders live (beside the packages, or inside an install)."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCENES_DIR = ROOT / "scenes"
SHADERS_DIR = ROOT / "shaders"
DEFAULT_SCENE = SCENES_DIR / "house.toml"
