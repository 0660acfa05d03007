"""mkdocs hook: warn (an error under ``--strict``) when a module of the packages has no ``::: module`` line.

Every module of ``sb3_aac`` and of the env packages is rendered on exactly one page: an algorithm's modules on its
algorithm page (SarsaAAC's on ``docs/api/sarsa_aac.md``), the rest on an API reference page. A module added without a
line in some page fails the build with a message saying where to add it. Package ``__init__`` files (re-exports) and
the modules in :data:`NOT_RENDERED` are exempt.
"""

from __future__ import annotations

import logging
import re
from pathlib import Path
from typing import Any

from mkdocs.config.defaults import MkDocsConfig

PACKAGES = {
    "sb3_aac": Path("sb3_aac"),
    "robocup_dribble": Path("envs/robocup_dribble"),
    "hybrid_domains": Path("envs/hybrid_domains"),
    "half_field_offense": Path("envs/half_field_offense"),
}
# module or package (with all its modules) -> the page that documents it instead of an API rendering
NOT_RENDERED = {
    "sb3_aac.cli": "cli.md (the help text of every command)",
}
AUTODOC = re.compile(r"^::: *([\w.]+)", flags=re.MULTILINE)

log = logging.getLogger("mkdocs.hooks.api_coverage")


def package_modules(root: Path) -> list[str]:
    """The dotted names of the non-package modules of :data:`PACKAGES` under the repository ``root``."""
    modules = []
    for name, directory in PACKAGES.items():
        for path in sorted((root / directory).rglob("*.py")):
            if path.name != "__init__.py":
                parts = path.relative_to(root / directory).with_suffix("").parts
                modules.append(".".join((name, *parts)))
    return modules


def on_post_build(config: MkDocsConfig, **kwargs: Any) -> None:
    root = Path(config.config_file_path).parent
    rendered = set()
    for page in Path(config.docs_dir).rglob("*.md"):
        rendered.update(AUTODOC.findall(page.read_text(encoding="utf-8")))
    for module in package_modules(root):
        if any(module == name or module.startswith(name + ".") for name in NOT_RENDERED):
            continue
        if not any(name == module or name.startswith(module + ".") for name in rendered):
            log.warning(
                f"Module {module} is on no page: add a line '::: {module}' to its algorithm page or to a page of "
                "docs/api/ (or exempt it in docs/hooks/api_coverage.py)"
            )
