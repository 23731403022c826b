"""Static checks as tests, so the README's test command enforces them."""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.skipif(
    shutil.which("ruff") is None and not (Path(sys.executable).parent / "ruff").exists(), reason="ruff not installed"
)
def test_ruff_clean():
    ruff = shutil.which("ruff") or str(Path(sys.executable).parent / "ruff")
    res = subprocess.run([ruff, "check", "src", "tests", "benchmarks"], cwd=ROOT, capture_output=True, text=True)
    assert res.returncode == 0, res.stdout + res.stderr


def _tool(name: str) -> str | None:
    return shutil.which(name) or (
        str(Path(sys.executable).parent / name) if (Path(sys.executable).parent / name).exists() else None
    )


@pytest.mark.skipif(_tool("mypy") is None, reason="mypy not installed")
@pytest.mark.slow
def test_mypy_clean():
    res = subprocess.run(
        [_tool("mypy"), "src/crmgrasp", "--cache-dir=/dev/null"], cwd=ROOT, capture_output=True, text=True
    )
    assert res.returncode == 0, res.stdout + res.stderr


def test_the_package_ships_its_data_and_its_typing_marker():
    """Every file pyproject.toml lists as package data exists, and ``py.typed`` (PEP 561) is one
    of them, so that a user's type checker reads crmgrasp's annotations."""
    import tomllib

    data = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]["crmgrasp"]
    assert "py.typed" in data
    for name in data:
        assert (ROOT / "src" / "crmgrasp" / name).is_file(), name
