"""Packaging: one version, an SPDX licence, and a wheel of the three packages only."""

import subprocess
import sys
import tomllib
from pathlib import Path

import setuptools

import ddgjax

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())


def test_python_m_ddgjax_version_prints_the_package_version():
    out = subprocess.run([sys.executable, "-m", "ddgjax", "--version"], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0 and out.stdout.strip() == f"ddgjax {ddgjax.__version__}"


def test_the_version_has_one_source():
    project = PYPROJECT["project"]
    assert "version" not in project and "version" in project["dynamic"]
    assert PYPROJECT["tool"]["setuptools"]["dynamic"]["version"] == {"attr": "ddgjax.__version__"}


def test_licence_is_an_spdx_expression_with_its_file():
    """The `project.license` table is deprecated (PEP 639): a string, and the text shipped."""
    project = PYPROJECT["project"]
    assert project["license"] == "MIT" and (ROOT / project["license-files"][0]).read_text().startswith("MIT License")


def test_wheel_holds_the_three_packages_and_nothing_else():
    include = PYPROJECT["tool"]["setuptools"]["packages"]["find"]["include"]
    top_level = {name.split(".")[0] for name in setuptools.find_packages(str(ROOT), include=include)}
    assert top_level == {"ddgjax", "energies", "solvers"}
    assert not (ROOT / "tests" / "__init__.py").exists() and not (ROOT / "benchmarks" / "__init__.py").exists()
