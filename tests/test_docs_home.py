"""The site's home page is the README (docs/hooks/readme_home.py): docs/index.md holds nothing of its own, and every
link of the README resolves on the site."""

from __future__ import annotations

import re
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "docs" / "hooks"))

from readme_home import MARKER, home_markdown  # noqa: E402


def test_the_home_page_is_the_readme() -> None:
    assert (REPO / "docs" / "index.md").read_text().strip() == MARKER


def test_every_link_of_the_home_page_resolves_on_the_site() -> None:
    home = home_markdown((REPO / "README.md").read_text())
    targets = [t.split("#")[0] for t in re.findall(r"\]\(([^)\s]+)\)", home) if not t.startswith(("http", "#"))]
    assert targets, "the README links to the docs"
    for target in targets:
        on_site = REPO / "benchmarks" / target if target.startswith("results/") else REPO / "docs" / target
        assert on_site.exists(), f"{target} is not a page of the site"


def test_the_home_page_names_every_algorithm_and_the_domains() -> None:
    home = home_markdown((REPO / "README.md").read_text())
    for name in ("SarsaAAC", "P-DQN", "MP-DQN", "HybridPPO", "DeepPolicy", "TilePolicy", "sb3-aac tune", "Goal-v0"):
        assert name in home, name
