"""The package's layers and boundaries (issue 20, item 1).

- The layers contract in ``pyproject.toml`` (``[tool.importlinter]``), checked by
  import-linter: a package imports only from the layers below it, function-level
  imports included, with no exception (``ignore_imports`` is empty and stays so).
- No private name (``_x``) is imported from another top-level package or module.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).parents[2]
PACKAGE = ROOT / "src" / "pneumact"


def test_the_layers_contract_holds():
    from importlinter.cli import lint_imports

    assert lint_imports(config_filename=str(ROOT / "pyproject.toml"),
                        no_cache=True) == 0, "run `lint-imports` for the broken imports"


def test_the_layers_contract_has_no_exception():
    import tomllib

    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    for contract in config["tool"]["importlinter"]["contracts"]:
        assert not contract.get("ignore_imports"), (
            f"contract {contract['id']!r} ignores imports: move the code instead")


def _top_package(module: str) -> str:
    """'pneumact.io.records' -> 'io'; 'pneumact.plotting' -> 'plotting'."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def private_imports_across_packages(root: Path = PACKAGE) -> list[tuple[str, str, str]]:
    """(importing module, imported module, name) for every ``from X import _name`` where
    X lies in another top-level package or module of pneumact."""
    found = []
    for path in sorted(root.rglob("*.py")):
        parts = list(path.relative_to(root.parent).with_suffix("").parts)
        package = parts[:-1]  # what a relative import is relative to
        module = ".".join(parts if parts[-1] != "__init__" else parts[:-1])
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not isinstance(node, ast.ImportFrom):
                continue
            if node.level:
                base = package[: len(package) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if not target.startswith("pneumact"):
                continue
            for alias in node.names:
                private = alias.name.startswith("_") and not alias.name.startswith("__")
                if private and _top_package(target) != _top_package(module):
                    found.append((module, target, alias.name))
    return found


def test_no_private_name_is_imported_across_packages():
    assert private_imports_across_packages() == []


def test_the_private_name_check_finds_one(tmp_path):
    package = tmp_path / "pneumact"
    (package / "io").mkdir(parents=True)
    (package / "__init__.py").write_text("")
    (package / "io" / "__init__.py").write_text("")
    (package / "io" / "tables.py").write_text("from ..plotting import _hidden\n"
                                              "from .files import _own\n")
    assert private_imports_across_packages(package) == [
        ("pneumact.io.tables", "pneumact.plotting", "_hidden")]
