"""MkDocs hooks of the site (``hooks:`` in mkdocs.yml).

- ``docs/scenarios.md`` gets the scenario reference, generated from the code at every build,
  where it says ``<!-- scenario-reference -->`` (see ``scenario_reference.py`` beside this).
- Pages that other work streams write (``PAGES_WRITTEN_ELSEWHERE``) may be missing from a
  checkout for a while; the nav leaves them out until they exist instead of failing the
  strict build. Any other missing page still fails it.
"""

from __future__ import annotations

import logging
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))

import scenario_reference

log = logging.getLogger("mkdocs.hooks.fleet_async")

PAGES_WRITTEN_ELSEWHERE = frozenset({"porting.md", "missions.md"})


def _prune(nav: Any, docs_dir: Path) -> Any:
    if isinstance(nav, list):
        kept = [_prune(item, docs_dir) for item in nav]
        return [item for item in kept if item is not None]
    if isinstance(nav, dict):
        kept = {title: _prune(target, docs_dir) for title, target in nav.items()}
        return {title: target for title, target in kept.items() if target is not None} or None
    if isinstance(nav, str) and nav in PAGES_WRITTEN_ELSEWHERE and not (docs_dir / nav).exists():
        log.info("nav: %s is not written yet; leaving it out", nav)
        return None
    return nav


def on_config(config: Any) -> Any:
    config.nav = _prune(config.nav, Path(config.docs_dir))
    return config


def on_page_markdown(markdown: str, page: Any, config: Any, files: Any) -> str:
    if page.file.src_uri == "scenarios.md":
        if scenario_reference.MARKER not in markdown:
            log.warning(
                "scenarios.md has no %s marker for the reference", scenario_reference.MARKER
            )
            return markdown
        return markdown.replace(scenario_reference.MARKER, scenario_reference.render())
    return markdown
