"""Packaging: what pyproject.toml declares is what gets installed, and the tests use it.

The source-tree checks run everywhere. The checks of the installed distribution need a
regular (non-editable) install and the tests run from ``tests/`` (README, ``.ci/run``);
with an editable install they are skipped with the reason shown by ``-ra``.
"""

import json
import sys
import tomllib
from fnmatch import fnmatch
from importlib import import_module, metadata
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = ROOT / "pyproject.toml"
DIST = "anchorplan"
TOP_LEVEL = ("placement", "analysis", "simulation")


def _config() -> dict:
    if not PYPROJECT.is_file():
        pytest.skip(f"{PYPROJECT} not found: the tests are not in a source checkout")
    return tomllib.loads(PYPROJECT.read_text())


def _source_packages(cfg: dict) -> dict[str, Path]:
    """Packages of the source tree that setuptools' find with ``include`` selects."""
    include = cfg["tool"]["setuptools"]["packages"]["find"]["include"]
    found: dict[str, Path] = {}

    def walk(path: Path, name: str) -> None:
        if not (path / "__init__.py").is_file():
            return
        if any(fnmatch(name, pattern) for pattern in include):
            found[name] = path
        for sub in sorted(path.iterdir()):
            if sub.is_dir() and sub.name != "__pycache__":
                walk(sub, f"{name}.{sub.name}")

    for top in sorted(ROOT.iterdir()):
        if top.is_dir():
            walk(top, top.name)
    return found


def _package_data(cfg: dict) -> dict[str, list[str]]:
    return cfg["tool"].get("setuptools", {}).get("package-data", {})


def _installed_distribution() -> metadata.Distribution:
    # an in-tree build leaves anchorplan.egg-info in the source tree: that is not an install
    dists = [
        d
        for d in metadata.distributions(name=DIST)
        if Path(str(d.locate_file(""))).resolve() != ROOT
    ]
    if not dists:
        pytest.skip(f"{DIST} is not installed (pip install '.[test]')")
    dist = dists[0]
    direct = dist.read_text("direct_url.json")
    if direct and json.loads(direct).get("dir_info", {}).get("editable"):
        pytest.skip(f"{DIST} is installed editable: the installed files are the source tree")
    return dist


def test_source_tree_has_the_declared_packages_and_package_data():
    cfg = _config()
    packages = _source_packages(cfg)
    assert set(TOP_LEVEL) <= set(packages), sorted(packages)
    for package, patterns in _package_data(cfg).items():
        assert package in packages, f"package-data for {package!r}, which is not a package"
        for pattern in patterns:
            matches = [p for p in packages[package].glob(pattern) if p.is_file()]
            assert matches, f"package-data {package}: {pattern!r} matches no file"


def test_installed_distribution_has_every_module_and_data_file():
    cfg = _config()
    dist = _installed_distribution()
    assert dist.files, f"{DIST}: the installed distribution lists no files (RECORD missing)"
    installed = {f.as_posix() for f in dist.files}
    expected = []
    for package, path in _source_packages(cfg).items():
        expected += [p.relative_to(ROOT).as_posix() for p in sorted(path.glob("*.py"))]
        for pattern in _package_data(cfg).get(package, []):
            expected += [
                p.relative_to(ROOT).as_posix() for p in sorted(path.glob(pattern)) if p.is_file()
            ]
    missing = [f for f in expected if f not in installed]
    assert not missing, f"in the source tree but not in the distribution: {missing}"
    absent = [f for f in expected if not Path(str(dist.locate_file(f))).is_file()]
    assert not absent, f"listed by the distribution but not on disk: {absent}"
    assert dist.entry_points.select(group="console_scripts", name="anchorplan")
    assert any(Path(str(f)).name == "LICENSE" for f in dist.files)


def test_the_tests_import_the_installed_packages():
    sources = _source_packages(_config())
    dist = _installed_distribution()
    site = Path(str(dist.locate_file(""))).resolve()
    for name in TOP_LEVEL:
        where = Path(import_module(name).__file__).resolve()
        assert where.is_relative_to(site), (
            f"{name} imported from {where}, not from the installed copy in {site}; "
            "run the tests from tests/ as the README says"
        )
        assert not where.is_relative_to(sources[name].resolve()), f"{name} from {where}"
    assert not any(Path(p or ".").resolve() == ROOT for p in sys.path), (
        f"the source tree {ROOT} is on sys.path"
    )
