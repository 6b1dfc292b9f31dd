"""Project conventions: licence, citation, changelog, one version, tool configuration, CI
entry point, no issue numbers in code."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import visprim

REPO = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))
CARGO = tomllib.loads((REPO / "Cargo.toml").read_text(encoding="utf-8"))


def text(name: str) -> str:
    return (REPO / name).read_text(encoding="utf-8")


def test_licence_is_mit_everywhere():
    assert text("LICENSE").startswith("MIT License")
    assert PYPROJECT["project"]["license"] == {"text": "MIT"}
    assert CARGO["package"]["license"] == "MIT"


def test_version_is_written_once():
    """Cargo.toml holds the version; pyproject takes it from there (maturin) and
    visprim.__version__ from the installed metadata (or Cargo.toml in a source tree)."""
    assert "version" not in PYPROJECT["project"]
    assert "version" in PYPROJECT["project"]["dynamic"]
    assert visprim.__version__ == CARGO["package"]["version"]
    literal = re.compile(r"""__version__\s*(:\s*str\s*)?=\s*["']""")
    for path in (REPO / "python").rglob("*.py"):
        assert not literal.search(path.read_text(encoding="utf-8")), path
    assert not re.search(r"(?m)^version:", text("CITATION.cff"))


def test_citation_cites_the_paper_and_the_project():
    cff = text("CITATION.cff")
    assert cff.startswith("cff-version: 1.2.0")
    assert re.search(r"(?m)^title: .*visprim", cff) and re.search(r"(?m)^type: software", cff)
    assert "preferred-citation:" in cff
    for needed in (
        "Automated Derivation of Primitives for Movement Classification",
        "journal: Autonomous Robots",
        "volume: 12",
        "year: 2002",
        "doi: 10.1023/A:1013254724861",
        "Visual Primitives for Imitation Learning",
        "family-names: Fod",
        "family-names: Jenkins",
    ):
        assert needed in cff, needed


def test_changelog_has_an_unreleased_section():
    log = text("CHANGELOG.md")
    assert log.startswith("# Changelog")
    assert "## [Unreleased]" in log
    assert f"## [{CARGO['package']['version']}]" in log


def test_mypy_configuration():
    mypy = PYPROJECT["tool"]["mypy"]
    assert mypy["files"] == ["python/visprim"]
    assert "ignore_missing_imports" not in mypy  # never globally
    ignored = set()
    for override in mypy["overrides"]:
        if override.get("ignore_missing_imports"):
            ignored |= set(override["module"])
    # Only packages without type information: dartpy, and the optional video extra's encoder
    # and pose estimator.
    assert "dartpy" in ignored
    assert ignored <= {"dartpy", "ezc3d", "imageio_ffmpeg", "mediapipe", "mediapipe.*"}
    dev = " ".join(PYPROJECT["project"]["optional-dependencies"]["dev"])
    for package in ("mypy", "scipy-stubs", "types-tqdm", "sphinx", "numpydoc"):
        assert package in dev, package


def test_ci_runs_tests_lint_and_docs():
    ci = text(".ci/run")
    assert re.findall(r"(?m)^make ([\w-]+)$", ci) == ["test", "lint", "docs", "wheel-check"]
    makefile = text("Makefile")
    lint = re.search(r"(?ms)^lint:.*?(?=^\S)", makefile)
    docs = re.search(r"(?ms)^docs:.*?(?=^\S)", makefile)
    assert lint and "mypy" in lint.group(0) and "ruff check" in lint.group(0)
    assert docs and "sphinx -W" in docs.group(0)
    # A fresh environment: a cached page would hide its warnings (one that another page's
    # change brings) from a build in a tree that was built before.
    assert " -E " in docs.group(0)
    assert (REPO / "docs" / "conf.py").is_file()


def test_wheel_check_uses_the_wheel_outside_the_tree():
    makefile = text("Makefile")
    check = re.search(r"(?ms)^wheel-check:.*?(?=^\S)", makefile)
    assert check, "no wheel-check target"
    recipe = check.group(0)
    assert "wheel" in recipe.split(":", 1)[1].split("\n")[0] and ".ci/wheel-check" in recipe
    script = text(".ci/wheel-check")
    for needed in ("mktemp -d", "venv", "visprim --version", "visprim -q learn --generated"):
        assert needed in script, needed
    assert 'cd "$tmp/work"' in script  # run from outside the source tree


def test_wheel_description_is_for_wheel_users():
    readme = PYPROJECT["project"]["readme"]
    assert readme != "README.md"
    description = text(readme)
    for absent in ("make ", "../shared", "benches/", "cargo "):
        assert absent not in description, absent
    for needed in ("authors", "classifiers", "keywords"):
        assert PYPROJECT["project"][needed], needed


def test_readme_opens_with_the_two_commands():
    readme = text("README.md")
    block = re.search(r"(?s)```\n(.*?)```", readme)
    assert block and readme.index("```") < readme.index("\n## ")
    commands = [line.split("#")[0].strip() for line in block.group(1).splitlines()]
    assert commands == ["make demo", "make test"]
    assert len(readme.splitlines()) <= 150


def test_tests_folder_is_plain():
    assert not (REPO / "tests" / "__init__.py").exists()


def test_no_issue_numbers_in_code():
    pattern = re.compile(r"(?i)\bissues? ?#?\d+")
    offenders = []
    for folder, ext in (
        ("python", "*.py"),
        ("tests", "*.py"),
        ("benches", "*.py"),
        ("rust", "*.rs"),
    ):
        for path in (REPO / folder).rglob(ext):
            for i, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
                if pattern.search(line) and path.name != "test_conventions.py":
                    offenders.append(f"{path.relative_to(REPO)}:{i}")
    assert offenders == []
