"""The package as a user gets it: sdist and wheel built (`python -m build`), checked
(`twine check`), the wheel installed in a fresh venv outside the checkout, and there:
`fieldtwin --version`, a run of the embedded plant, the dashboard page and its static
files, and docs/testing.md's example project with the installed pytest plugin."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import httpx
import pytest

from tests.control.plantproc import Running, fieldtwin_run_with
from tests.plugin.project import EXAMPLES, ROOT
from tests.plugin.test_testing_doc import files_on_the_page

STEP_S = 600
SKIP = shutil.ignore_patterns(
    ".git", ".venv", "__pycache__", "*.egg-info", ".mypy_cache", ".ruff_cache",
    ".pytest_cache", "test-artifacts", "build", "dist",
)  # fmt: skip


def _env() -> dict[str, str]:
    """No PYTHONPATH: the installed wheel is what runs, never the checkout's src."""
    return {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}


def _run(argv: list[str | Path], cwd: Path) -> str:
    done = subprocess.run(
        [str(a) for a in argv],
        capture_output=True,
        text=True,
        timeout=STEP_S,
        cwd=cwd,
        env=_env(),
        check=False,
    )
    assert done.returncode == 0, (argv, done.stdout[-3000:], done.stderr[-3000:])
    return done.stdout


@pytest.mark.integration
@pytest.mark.timeout(1800)
def test_the_wheel_installs_and_runs_outside_the_checkout(tmp_path: Path) -> None:
    version = tomllib.loads((ROOT / "pyproject.toml").read_text("utf-8"))["project"]["version"]
    source = tmp_path / "source"  # a copy: the build writes nothing into the checkout
    shutil.copytree(ROOT, source, ignore=SKIP)
    venv = tmp_path / "venv"
    _run([sys.executable, "-m", "venv", venv], tmp_path)
    py, bin_ = venv / "bin" / "python", venv / "bin"
    _run([py, "-m", "pip", "install", "-q", "build", "twine"], tmp_path)
    dist = tmp_path / "dist"
    _run([py, "-m", "build", "--outdir", dist, source], tmp_path)
    sdist = sorted(dist.glob("fieldtwin-*.tar.gz"))
    wheel = sorted(dist.glob("fieldtwin-*.whl"))
    assert len(sdist) == 1 and len(wheel) == 1, sorted(dist.iterdir())
    assert f"fieldtwin-{version}" in wheel[0].name
    assert "PASSED" in _run([bin_ / "twine", "check", *sdist, *wheel], tmp_path)
    _run(
        [py, "-m", "pip", "install", "-q", "--find-links", dist, f"fieldtwin=={version}",
         "pytest", "pymodbus~=3.16.1"],
        tmp_path,
    )  # fmt: skip
    away = tmp_path / "elsewhere"
    away.mkdir()
    where = _run([py, "-c", "import fieldtwin; print(fieldtwin.__file__)"], away)
    assert str(venv) in where and str(ROOT) not in where, where

    assert _run([bin_ / "fieldtwin", "--version"], away).strip() == f"fieldtwin {version}"

    plant = away / "default.toml"  # the embedded plant as installed, on free ports
    text = _run(
        [py, "-c", "from importlib import resources; print(resources.files('fieldtwin')"
         ".joinpath('plants', 'default.toml').read_text('utf-8'), end='')"],
        away,
    )  # fmt: skip
    plant.write_text(text.replace("tcp://127.0.0.1:5020", "tcp://127.0.0.1:0"), "utf-8")
    out = _run(
        [bin_ / "fieldtwin", "run", plant, "--duration", "2", "--speed", "max", "--no-live",
         "--control-port", "0"],
        away,
    )  # fmt: skip
    assert out.splitlines()[-1].startswith("stopped at t = 2."), out

    with fieldtwin_run_with([str(bin_ / "fieldtwin")], plant, away, _env()) as running:
        _dashboard_and_its_files(running)

    project = tmp_path / "project"
    for name, body in files_on_the_page().items():
        path = project / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(body, "utf-8")
    shutil.copy(EXAMPLES / "aem811_tank.pl7", project / "plants" / "aem811_tank.pl7")
    out = _run([py, "-m", "pytest", "-p", "no:cacheprovider", "-q", "-rA"], project)
    assert re.search(r"\b\d+ passed\b", out) and " failed" not in out, out


def _dashboard_and_its_files(running: Running) -> None:
    page = httpx.get(running.url + "/", timeout=30)
    assert page.status_code == 200, page.text[:500]
    assets = sorted(set(re.findall(r'(?:src|href)="(/static/[^"]+)"', page.text)))
    assert any(".js" in a for a in assets) and any(".css" in a for a in assets), assets
    for asset in assets:
        got = httpx.get(running.url + asset, timeout=30)
        assert got.status_code == 200 and got.content, asset
