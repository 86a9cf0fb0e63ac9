"""mkdocs hook: the notebooks page is written from the notebooks themselves.

`docs/notebooks.md` holds the marker `<!-- notebooks -->`; this hook replaces it with the opening markdown
cell of every `notebooks/NN_*.py` (jupytext percent format), so the page never drifts from the notebooks.
Plain Python (mkdocs >= 1.4 `hooks:`), no plugin needed.
"""

from __future__ import annotations

from pathlib import Path

MARKER = "<!-- notebooks -->"
ROOT = Path(__file__).resolve().parents[2]


def opening_cell(path: Path) -> str:
    """The first `# %% [markdown]` cell of a percent-format notebook, as markdown (headings one level down)."""
    out, inside = [], False
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.startswith("# %% [markdown]"):
            inside = True
            continue
        if inside and line.startswith("# %%"):
            break
        if inside:
            text = line[2:] if line.startswith("# ") else line.lstrip("#")
            out.append("#" + text if text.startswith("#") else text)
    return "\n".join(out).strip()


def notebooks_markdown() -> str:
    parts = []
    for path in sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.py")):
        parts.append(opening_cell(path) + f"\n\nSource: `notebooks/{path.name}`.\n")
    return "\n".join(parts)


def on_page_markdown(markdown: str, page, config, files) -> str:  # noqa: ARG001 (mkdocs hook signature)
    if MARKER in markdown:
        return markdown.replace(MARKER, notebooks_markdown())
    return markdown
