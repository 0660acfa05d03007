"""mkdocs hook: publish the committed benchmark reports and their figures (``benchmarks/results`` and the presets'
folders in it, such as ``hfo/``) under ``results/``.

The report is written by ``python -m benchmarks.report``; serving it from where it is committed keeps a single
copy, and its relative figure links keep working.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from mkdocs.config.defaults import MkDocsConfig
from mkdocs.structure.files import File, Files

RESULTS = Path("benchmarks/results")
PUBLISHED = ("report.md", "*.png", "*/report.md", "*/*.png")


def on_files(files: Files, config: MkDocsConfig, **kwargs: Any) -> Files:
    root = Path(config.config_file_path).parent / RESULTS
    for pattern in PUBLISHED:
        for path in sorted(root.glob(pattern)):
            name = path.relative_to(root).as_posix()
            files.append(File.generated(config, f"results/{name}", abs_src_path=str(path)))
    return files
