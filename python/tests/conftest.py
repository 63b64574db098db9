"""Shared fixtures: the repository's root and the `hairfit` command line built from the same
source as the package, so the tests compare the bindings with the CLI bit for bit."""

import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "data"


@pytest.fixture(scope="session")
def cli() -> Path:
    """The release binary the package is compared with: HAIRFIT_BIN, else
    target/release/hairfit (CI's `cargo test --release` builds it), built with `cargo build
    --release` when missing or older than a source file (a plain build resolves features
    without the dev-dependencies, so right after `cargo test --release` it would recompile the
    library: skipped when the binary is current)."""
    given = os.environ.get("HAIRFIT_BIN")
    if given:
        return Path(given)
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    binary = target / "release" / "hairfit"
    sources = [ROOT / "Cargo.toml", ROOT / "Cargo.lock", *(ROOT / "src").rglob("*.rs")]
    newest = max(p.stat().st_mtime for p in sources)
    if not binary.exists() or binary.stat().st_mtime < newest:
        subprocess.run(["cargo", "build", "--release", "--bin", "hairfit"], cwd=ROOT, check=True)
    return binary


def run_cli(cli: Path, *args, check: bool = True, cwd=None) -> subprocess.CompletedProcess:
    """Run the command line; its completed process (text stdout/stderr)."""
    result = subprocess.run(
        [str(cli), *map(str, args)], capture_output=True, text=True, cwd=cwd
    )
    if check and result.returncode != 0:
        raise AssertionError(f"hairfit {args} failed ({result.returncode}):\n{result.stderr}")
    return result


def cli_error(cli: Path, *args, cwd=None) -> str:
    """The message the CLI prints for a failing command, without `hairfit: error: `."""
    result = run_cli(cli, *args, check=False, cwd=cwd)
    assert result.returncode == 1, (result.returncode, result.stderr)
    lines = [l for l in result.stderr.splitlines() if l.startswith("hairfit: error: ")]
    assert len(lines) == 1, result.stderr
    return lines[0][len("hairfit: error: "):]
