"""The repository's own docs hold what its code and docs cite: every
``docs/<file>.md`` named in a tracked file exists, and every section cited as
``docs/<file>.md, *Title*`` (or ``(*Title*)``, or ``"Title"``) is a heading, a
bold lead (``**Title.**``) or an italic paragraph lead (``*Title.*``) of that
file. A section renamed or moved without its citations fails here, naming the
file that cites it."""
import os
import re
import subprocess

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DOCS = os.path.join(ROOT, "docs")
SOURCES = (".py", ".pyi", ".cpp", ".h", ".glsl", ".frag", ".vert", ".comp", ".sh", ".md", ".txt", ".toml",
           ".cmake")
NAMED = re.compile(r"docs/([A-Za-z0-9_.-]+\.md)")
CITED = re.compile(r'docs/([A-Za-z0-9_.-]+\.md)(?:[,:]\s*\(?\s*|\s*\(\s*|\s+)(?:\*([^*]+)\*|"([A-Z][^"]*)")')


def tracked_sources():
    try:
        out = subprocess.run(["git", "-C", ROOT, "ls-files"], capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git checkout: the tracked files are unknown")
    return [f for f in out.split() if f.endswith(SOURCES) or os.path.basename(f) == "CMakeLists.txt"]


def unwrapped(text):
    """Comment and string continuations joined into one line, so that a title
    wrapped over lines (``# ... *The\\n# coarse levels*``) reads as one."""
    text = re.sub(r'\\n"\s*\n\s*"', " ", text)  # C and Python adjacent literals ending in \n
    text = re.sub(r'"\s*\n\s*"', "", text)
    return re.sub(r"\n[ \t]*(?:#+|//+|\*(?!\*)|-)?[ \t]*", " ", text)


def section_titles(name):
    with open(os.path.join(DOCS, name), encoding="utf-8") as f:
        text = f.read()
    titles = {m.group(1).strip() for m in re.finditer(r"^#+\s+(.+?)\s*$", text, re.M)}
    titles |= {" ".join(m.group(1).split()).rstrip(".:") for m in re.finditer(r"\*\*([^*]+?)\*\*", text)}
    titles |= {m.group(1).strip().rstrip(".:") for m in re.finditer(r"^\*([^*\n]+?)\*", text, re.M)}
    return titles


def read(path):
    try:
        with open(os.path.join(ROOT, path), encoding="utf-8") as f:
            return f.read()
    except (UnicodeDecodeError, FileNotFoundError):
        return ""


def test_every_cited_doc_and_section_exists():
    files = tracked_sources()
    missing_files, missing_sections, checked = [], [], 0
    titles = {}
    for path in files:
        text = read(path)
        for m in NAMED.finditer(text):
            if not os.path.isfile(os.path.join(DOCS, m.group(1))):
                missing_files.append(f"{path}: docs/{m.group(1)}")
        for m in CITED.finditer(unwrapped(text)):
            name, title = m.group(1), " ".join((m.group(2) or m.group(3)).split())
            if not os.path.isfile(os.path.join(DOCS, name)):
                continue  # reported above
            if name not in titles:
                titles[name] = section_titles(name)
            checked += 1
            if not any(t == title or t.startswith(title) for t in titles[name]):
                missing_sections.append(f"{path}: docs/{name}, *{title}*")
    assert not missing_files, "cited docs that do not exist:\n" + "\n".join(sorted(set(missing_files)))
    assert not missing_sections, "cited sections their docs do not have:\n" + "\n".join(missing_sections)
    assert checked > 50, f"only {checked} section citations found: the pattern no longer matches how they are written"


def test_the_check_fails_on_a_missing_section(tmp_path):
    """The matcher itself: a title the doc has passes, one it lacks does not."""
    assert "Hidden sides" in section_titles("addon.md")
    assert not any(t.startswith("A section nobody wrote") for t in section_titles("addon.md"))
    d = "docs/"  # not written out, or this file would cite those sections itself
    cited = CITED.findall(unwrapped(f'// see {d}addon.md, *Hidden\n// sides* and {d}marches.md (*Convex creases*),\n'
                                    f'// {d}marches.md, "The exact march"'))
    assert cited == [("addon.md", "Hidden sides", ""), ("marches.md", "Convex creases", ""),
                     ("marches.md", "", "The exact march")]
