"""The reports package's structure (issue 40, item 4): one list of sections with their titles, sections that do not
import each other, no private name imported across modules. Read from the source, so no report is built."""

from __future__ import annotations

import ast
from pathlib import Path

import reports
from reports.content import BUILDERS
from reports.outline import SECTIONS

PACKAGE = Path(reports.__file__).parent


def _imports(path: Path) -> list[tuple[str, str]]:
    """Every ``(module, name)`` a file imports, at any depth (lazy imports inside functions included); ``name`` is
    empty for ``import module``."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            found += [(node.module or "", alias.name) for alias in node.names]
        elif isinstance(node, ast.Import):
            found += [(alias.name, "") for alias in node.names]
    return found


def test_no_section_imports_another():
    """What two sections share lives beside them (reports.phrases, reports.detection, reports.ranking, the builder),
    so a section can be moved, dropped or rewritten alone. The import-linter contract in pyproject.toml says the
    same; this test holds while it is not there."""
    sections = sorted((PACKAGE / "sections").glob("*.py"))
    names = {p.stem for p in sections} - {"__init__"}
    for path in sections:
        for module, name in _imports(path):
            imported = {module.removeprefix("reports.sections.")} if module.startswith("reports.sections.") else (
                {name} if module == "reports.sections" else set())
            assert not imported & names, f"reports/sections/{path.name} imports the section {imported & names}"


def test_no_private_name_is_imported_across_modules():
    for path in sorted(PACKAGE.rglob("*.py")):
        private = [f"{module}.{name}" for module, name in _imports(path) if name.startswith("_")]
        assert not private, f"{path.relative_to(PACKAGE.parent)} imports private names: {private}"


def test_one_list_of_sections_with_a_builder_each():
    keys = [entry.key for entry in SECTIONS]
    assert len(set(keys)) == len(keys)
    assert set(BUILDERS) == set(keys)  # a builder for every section, no section outside the list
    assert {entry.needs for entry in SECTIONS} == {"", "comparison", "measured"}
    assert keys[-1] == "summary"  # provenance and the configuration's long tables come after every result (issue 42)
