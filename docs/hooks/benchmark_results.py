"""mkdocs hook: publish the committed benchmark report and its figures (``benchmarks/results``) under ``results/``.

The report is written by ``python -m benchmarks.report``; serving it from where it is committed keeps a single
copy, and its relative figure links keep working.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from mkdocs.config.defaults import MkDocsConfig
from mkdocs.structure.files import File, Files

RESULTS = Path("benchmarks/results")
PUBLISHED = ("report.md", "*.png")


def on_files(files: Files, config: MkDocsConfig, **kwargs: Any) -> Files:
    root = Path(config.config_file_path).parent / RESULTS
    for pattern in PUBLISHED:
        for path in sorted(root.glob(pattern)):
            files.append(File.generated(config, f"results/{path.name}", abs_src_path=str(path)))
    return files
