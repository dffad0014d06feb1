"""MkDocs hook (mkdocs.yml's ``hooks``): a nav entry with a wildcard, such as ``envs/*.md``, stands for the pages it
matches that the nav names nowhere else, sorted by name regardless of case. An env page or a system's physics page
then joins the nav by being written, and mkdocs.yml names no env."""

from __future__ import annotations

from pathlib import Path


def named(nav) -> list[str]:
    """Every page a nav (a list of pages and sections) names, wildcards included."""
    if isinstance(nav, str):
        return [nav]
    items = nav.values() if isinstance(nav, dict) else nav
    return [page for item in items for page in named(item)]


def expanded(nav, docs: Path, taken: set[str]):
    """The nav with each wildcard entry replaced by the pages under docs that it matches and `taken` leaves out."""
    if isinstance(nav, str):
        return nav
    if isinstance(nav, dict):
        return {title: expanded(item, docs, taken) for title, item in nav.items()}
    pages = []
    for item in nav:
        if isinstance(item, str) and "*" in item:
            matches = (path.relative_to(docs).as_posix() for path in docs.glob(item))
            pages += sorted((page for page in matches if page not in taken), key=str.casefold)
        else:
            pages.append(expanded(item, docs, taken))
    return pages


def on_config(config):
    config["nav"] = expanded(config["nav"], Path(config["docs_dir"]), set(named(config["nav"])))
    return config
