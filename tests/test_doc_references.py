"""Everything the README, the docs, the models and the sources cite lies inside the repository.

Three kinds of reference are checked:

* Markdown links and images, ``[text](target)``, relative to the citing file;
* repository paths in prose and code blocks, ``docs/...``, ``models/...``,
  ``blademodel/...``, ``benchmarks/...``, ``tests/...``, relative to the root
  (a ``*`` is a glob that must match something);
* the model statement, ``MODEL.md section 8`` / ``MODEL.md §4.2``: the file is
  ``docs/MODEL.md`` and the numbered section must exist in it.

and no file may point outside the checkout (the hand-over folder beside it, absolute
paths of this machine; ``OUTSIDE``).
"""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
MODEL_MD = ROOT / "docs" / "MODEL.md"

#: Paths cited on purpose that are not in the repository, with the reason.
NOT_IN_REPOSITORY = {
    "docs/_build/html": "the output folder of the docs build",
    "docs/_build/html/index.html": "the docs build's front page",
    "models/mine.yaml": "a user's file, in an example error message",
}

LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
REPO_PATH = re.compile(r"(?<![\w./(-])((?:docs|models|blademodel|benchmarks|tests|\.ci)/[\w./*<>-]*[\w/*>])")
MODEL_SECTION = re.compile(r"MODEL\.md`?,?\s+(?:section|§)\s*(\d+(?:\.\d+)?)")
OUTSIDE = re.compile(r"\.\./shared|/work/|/root/|/home/\w+/")


def _texts():
    files = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md")), *sorted((ROOT / "models").rglob("*.yaml")),
             *sorted((ROOT / "blademodel").rglob("*.py"))]
    return [(f, f.read_text()) for f in files if "_build" not in f.parts]


TEXTS = _texts()


def _exists(path: str) -> bool:
    if "<" in path:   # a placeholder such as out/<name>.nc
        return True
    if "*" in path:
        return any(ROOT.glob(path))
    return (ROOT / path).exists()


@pytest.mark.parametrize("path, text", [(f, t) for f, t in TEXTS if f.suffix == ".md"],
                         ids=lambda v: str(v.relative_to(ROOT)) if isinstance(v, Path) else "")
def test_markdown_links_resolve(path, text):
    broken = []
    for target in LINK.findall(text):
        if re.match(r"[a-z]+:", target) or target.startswith("#"):
            continue
        if not (path.parent / target.split("#")[0]).exists():
            broken.append(target)
    assert not broken, f"{path.relative_to(ROOT)} links to missing files: {broken}"


def test_repository_paths_resolve():
    broken = set()
    for path, text in TEXTS:
        if path.suffix == ".py":
            continue   # sources name their siblings by module, not by path
        for ref in REPO_PATH.findall(text):
            ref = ref.rstrip(".")
            if ref not in NOT_IN_REPOSITORY and not _exists(ref):
                broken.add(f"{path.relative_to(ROOT)}: {ref}")
    assert not broken, sorted(broken)


def test_model_statement_sections_exist():
    headings = set(re.findall(r"^#+\s+(\d+(?:\.\d+)?)[.\s]", MODEL_MD.read_text(), flags=re.M))
    cited = {(path.relative_to(ROOT), s) for path, text in TEXTS for s in MODEL_SECTION.findall(text)}
    assert len(cited) > 10   # the studies cite section 8; the pattern must keep finding them
    missing = sorted(f"{p}: section {s}" for p, s in cited if s not in headings)
    assert not missing, missing


def test_nothing_points_outside_the_checkout():
    found = [f"{path.relative_to(ROOT)}: {m.group(0)}" for path, text in TEXTS for m in OUTSIDE.finditer(text)]
    assert not found, found


def test_the_check_finds_a_broken_reference(tmp_path):
    """The patterns see the references they are meant to check."""
    text = "See `docs/nowhere.md`, [this](figures/none.png) and MODEL.md section 9."
    assert REPO_PATH.findall(text) == ["docs/nowhere.md"]
    assert LINK.findall(text) == ["figures/none.png"]
    assert MODEL_SECTION.findall(text) == ["9"]
