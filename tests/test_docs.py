"""The documentation: the MkDocs site builds with no warning, and the README stays a short front page that starts
with the two-command quick start."""
from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
README = (ROOT / "README.md").read_text(encoding="utf-8")


def test_the_site_builds_strictly(tmp_path):
    pytest.importorskip("mkdocs")
    pytest.importorskip("mkdocstrings")
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")
    res = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
                         cwd=ROOT, env=env, capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stdout + res.stderr
    assert not re.search(r"^WARNING\s+-", res.stderr, re.M), res.stderr  # mkdocs' own log lines (strict fails on them)
    for page in ("index.html", "tutorial/first-machine/index.html", "reference/machine/index.html"):
        assert (tmp_path / "site" / page).stat().st_size > 1000, page
    # mkdocstrings rendered the API from the docstrings
    assert "load_machine" in (tmp_path / "site" / "reference" / "machine" / "index.html").read_text(encoding="utf-8")


def test_the_readme_is_short_and_starts_with_the_quick_start():
    lines = README.splitlines()
    assert len(lines) <= 150, len(lines)
    m = re.match(r"# sewgen\n\n```bash\n(.*?)\n```\n", README, re.S)
    assert m, "README.md must start with its title and the quick start's ```bash block"
    commands = m.group(1).splitlines()
    assert len(commands) == 2, commands
    assert commands[0].startswith("pip install . && sewgen analyze jb1-3 --out jb1-3")
    assert commands[1].startswith('pip install -e ".[test]" && python -m pytest')


def test_every_reference_directive_is_alone_on_its_line():
    """docs/reference/*.md name modules by today's paths, one ``::: sewgen.xxx`` a line, so that a move of the
    modules is one substitution there."""
    for page in sorted((ROOT / "docs" / "reference").glob("*.md")):
        text = page.read_text(encoding="utf-8")
        directives = re.findall(r"^::: (\S+)$", text, re.M)
        assert directives, page.name
        assert text.count(":::") == len(directives), page.name
        for name in directives:
            assert name == "sewgen" or name.startswith("sewgen."), (page.name, name)
