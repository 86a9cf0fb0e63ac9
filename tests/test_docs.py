"""The repository stands alone (issue 17): nothing outside `docs/` cites files that live outside the
repository, every section of `docs/references.md` cited by name (the docs/references.md + comma +
quoted name form) is a heading there,
and every on-disk cache follows `HERTZ_CHAIN_CACHE_DIR` (`hertz_chain._cache.cache_dir`).

Reference: the file tree itself (`git ls-files`) and the headings of `docs/references.md`.
"""

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
REFS = ROOT / "docs" / "references.md"
# built from pieces so that this file does not match its own patterns
OUTSIDE = [".." + "/shared", "shared" + "/seed", "shared" + "/references.md"]
CITATION = re.compile(r'docs/references\.md`?,\s*\\?"+([^"\\]+)\\?"')
TEXT_SUFFIXES = {".py", ".md", ".csv", ".toml", ".txt", ".cfg", ".ini", ".json", ".yaml", ".yml", ""}


def _repo_files() -> list[Path]:
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("needs a git checkout to list the repository's files")
    out = subprocess.run(["git", "ls-files", "--cached", "--others", "--exclude-standard", "-z"], cwd=ROOT,
                         capture_output=True, check=True).stdout.decode()
    files = [ROOT / f for f in out.split("\0") if f]
    return [f for f in files if f.is_file() and (f.suffix in TEXT_SUFFIXES or f.name == "Makefile")]


def _headings() -> set[str]:
    return {m.group(1).strip() for m in re.finditer(r"^#{1,6}\s+(.+?)\s*$", REFS.read_text(encoding="utf-8"), re.M)}


def test_references_page_exists_with_sources():
    text = REFS.read_text(encoding="utf-8")
    assert "## Seed paper" in text and "Shock and Vibration" in text
    for tag in ("[paper]", "[pub]", "[num]", "[unverified]"):  # every fact says how sure it is
        assert tag in text


def test_nothing_outside_docs_cites_files_outside_the_repository():
    bad = []
    for f in _repo_files():
        rel = f.relative_to(ROOT).as_posix()
        if rel.startswith("docs/"):
            continue
        try:
            text = f.read_text(encoding="utf-8")
        except UnicodeDecodeError:
            continue
        for n, line in enumerate(text.splitlines(), 1):
            if any(p in line for p in OUTSIDE):
                bad.append(f"{rel}:{n}: {line.strip()[:120]}")
    assert not bad, "citations of files outside the repository:\n" + "\n".join(bad)


def test_cited_sections_exist():
    headings = _headings()
    cited = {}
    for f in _repo_files():
        if f == REFS:  # its introduction shows the form with a placeholder
            continue
        try:
            text = f.read_text(encoding="utf-8")
        except UnicodeDecodeError:
            continue
        for m in CITATION.finditer(text):
            cited.setdefault(m.group(1).strip(), f.relative_to(ROOT).as_posix())
    assert len(cited) >= 5  # the code, notebooks and tables do cite sections
    missing = {s: where for s, where in cited.items() if s not in headings}
    assert not missing, f"sections cited but not headings of docs/references.md: {missing}"


def test_citation_pattern_reads_python_and_csv_quoting():
    # a Python comment, an escaped quote inside a Python string, and a CSV field ("" escapes)
    for s in ['# docs/references.md, "Test levels"', r'"see docs/references.md, \"Test levels\", x"',
              '"docs/references.md, ""Test levels"" (secondary)"', '`docs/references.md, "Test levels"`']:
        assert [m.group(1) for m in CITATION.finditer(s)] == ["Test levels"], s


CACHE_SCRIPT = """
import json, os
from hertz_chain import _config
from hertz_chain.stackfile import parse_quantity
assert parse_quantity("1 cm", "length") == 0.01
import jax, jax.numpy as jnp
jax.jit(lambda x: jnp.sin(x) * 2.0)(jnp.arange(3.0)).block_until_ready()
print(json.dumps({"jax": _config.CACHE_DIR, "cache_dir": _config.cache_dir()}))
"""


def test_every_cache_follows_HERTZ_CHAIN_CACHE_DIR(tmp_path):
    root = tmp_path / "my cache"
    home = tmp_path / "xdg"  # the default location must stay empty
    env = {**os.environ, "HERTZ_CHAIN_CACHE_DIR": str(root), "XDG_CACHE_HOME": str(home)}
    env.pop("HERTZ_CHAIN_NO_CACHE", None)
    proc = subprocess.run([sys.executable, "-c", CACHE_SCRIPT], env=env, capture_output=True, text=True,
                          timeout=300, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert out["cache_dir"] == str(root)
    assert out["jax"] == str(root / "jax")
    assert any((root / "jax").iterdir())  # JAX's compilation cache wrote its entry
    assert any((root / "pint").iterdir())  # pint's parsed definitions
    assert not home.exists()


def test_no_cache_turns_every_cache_off(tmp_path):
    root = tmp_path / "cache"
    env = {**os.environ, "HERTZ_CHAIN_CACHE_DIR": str(root), "HERTZ_CHAIN_NO_CACHE": "1"}
    proc = subprocess.run([sys.executable, "-c", CACHE_SCRIPT], env=env, capture_output=True, text=True,
                          timeout=300, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert out == {"jax": None, "cache_dir": None}
    assert not root.exists()


def test_the_documentation_site_builds_strictly(tmp_path):
    # `make docs`: mkdocs-material + mkdocstrings, every warning (a broken link, an unresolved
    # reference, a page missing from the navigation) an error
    import os
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    mkdocs = Path(sys.executable).with_name("mkdocs")
    proc = subprocess.run([str(mkdocs), "build", "--strict", "--site-dir", str(tmp_path / "site")], cwd=root,
                          capture_output=True, text=True, timeout=300,
                          env=dict(os.environ, NO_MKDOCS_2_WARNING="1"))
    assert proc.returncode == 0, proc.stderr[-3000:]
    api = (tmp_path / "site" / "api" / "index.html").read_text()
    for name in ("simulate_batch", "launch_velocity", "LawRow", "Status", "load_stack_file"):
        assert name in api, name


def test_the_notebooks_page_is_written_from_every_notebook():
    # docs/hooks/notebooks.py replaces the page's marker with each notebook's opening cell
    import importlib.util

    spec = importlib.util.spec_from_file_location("nb_hook", ROOT / "docs" / "hooks" / "notebooks.py")
    hook = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(hook)
    page = (ROOT / "docs" / "notebooks.md").read_text(encoding="utf-8")
    out = hook.on_page_markdown(page, None, None, None)
    assert hook.MARKER in page and hook.MARKER not in out
    for path in sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.py")):
        title = hook.opening_cell(path).splitlines()[0]
        assert title.startswith("## ") and title in out, path.name
        assert f"notebooks/{path.name}" in out


# a fragment of a stack file in the docs (a section or two) is checked inside this minimal file: six masses
# of a material with a radius (for laws computed from them), run to a fixed t_max (a far wall needs it)
_BASE_FILE = {"drop": {"impact_velocity": "1 m/s"},
              "stack": {"masses": ["1 kg", "0.5 kg", "0.25 kg", "0.12 kg", "0.06 kg", "0.03 kg"], "gaps": 0,
                        "material": "steel-52100", "radius": "5 mm"},
              "contact": {"law": "hertz"}, "solver": {"until": "t_max", "t_max": "1 ms"}}


def _toml_blocks():
    for page in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        for i, m in enumerate(re.finditer(r"```toml\n(.*?)```", page.read_text(encoding="utf-8"), re.S)):
            yield pytest.param(m.group(1), id=f"{page.name}-{i}")


@pytest.mark.parametrize("text", list(_toml_blocks()))
def test_every_stack_file_in_the_docs_loads_and_builds(text):
    # a review ran the materials example of stack-files.md: its material names ("AISI 52100") were not in the
    # package's table; every block must parse and build, a whole file as it is, a fragment inside _BASE_FILE
    import copy
    import tomllib

    import hertz_chain as hc
    from hertz_chain.stackfile import parse_stack

    doc = tomllib.loads(text)
    whole = "contact" in doc and ({"masses", "design"} & set(doc.get("stack", {})))
    if not whole:
        merged = copy.deepcopy(_BASE_FILE)
        for key, value in doc.items():  # a fragment's section adds to the base's (its [contact] replaces it)
            if isinstance(value, dict) and key in merged and key != "contact":
                merged[key].update(value)
            else:
                merged[key] = value
        doc = merged
    hc.build(parse_stack(doc, source="docs"))
