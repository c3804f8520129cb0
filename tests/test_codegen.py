"""The code generator and the C it emits: up to date, deterministic, warning-free, self-describing, and
with no user names in the C namespace.
"""
from __future__ import annotations

import io
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from sewgen.derive.__main__ import check

pytestmark = [pytest.mark.derive]

ROOT = Path(__file__).resolve().parent.parent
GENERATED = ROOT / "generated"
CSRC = ROOT / "csrc"
GCC = shutil.which("gcc")
NM = shutil.which("nm")
CFLAGS = ["-std=c99", "-O2", "-Wall", "-Wextra", "-Werror"]
TEXT_SUFFIXES = {".c", ".h", ".cdef", ".json"}


def _committed_generated() -> list[Path]:
    """The files of generated/ under version control (build artifacts such as *.o are not)."""
    git = shutil.which("git")
    if git and (ROOT / ".git").exists():
        out = subprocess.run([git, "ls-files", "-z", "--", "generated"], cwd=ROOT, capture_output=True)
        if out.returncode == 0:
            files = [ROOT / name for name in out.stdout.decode().split("\0") if name]
            if files:
                return sorted(files)
    return sorted(p for p in GENERATED.iterdir() if p.is_file() and p.suffix in TEXT_SUFFIXES)


def _kernel_files() -> list[Path]:
    return [p for p in _committed_generated() if p.suffix == ".c"]


def _manifest() -> dict:
    return json.loads((GENERATED / "manifest.json").read_text(encoding="utf-8"))


def _copy_committed(dest: Path) -> Path:
    dest.mkdir(parents=True, exist_ok=True)
    for p in _committed_generated():
        shutil.copyfile(p, dest / p.name)
    return dest


# -- up to date and deterministic: the catalog is derived twice in this file, once per hash seed -----------------

@pytest.fixture(scope="module")
def derivations(tmp_path_factory):
    """Two derivations of the catalog at once, in processes with PYTHONHASHSEED 0 and 12345: the first is
    `python -m derive --check` on a copy of the committed files (as a developer or CI runs it), the second
    writes its files into a folder of its own. Returns (the check's result, the second's files by name)."""
    checked = _copy_committed(tmp_path_factory.mktemp("committed") / "generated")
    written = tmp_path_factory.mktemp("seed_12345") / "generated"
    env = dict(os.environ)
    procs = [subprocess.Popen([sys.executable, "-m", "derive", *args], cwd=ROOT, text=True,
                              env=dict(env, PYTHONHASHSEED=seed), stdout=subprocess.PIPE, stderr=subprocess.PIPE)
             for seed, args in (("0", ("--check", "--out", str(checked))), ("12345", ("--out", str(written))))]
    results = []
    for proc in procs:
        out, err = proc.communicate(timeout=300)
        results.append(subprocess.CompletedProcess(proc.args, proc.returncode, out, err))
    assert results[1].returncode == 0, results[1].stderr[-3000:]
    return results[0], {p.name: p.read_text() for p in written.iterdir() if p.is_file()}


def test_check_passes_on_the_committed_generated_files(derivations):
    """Only the version-controlled files of generated/ (no build artifacts), checked with --check --out."""
    res, _ = derivations
    assert res.returncode == 0, f"stdout:\n{res.stdout[-3000:]}\nstderr:\n{res.stderr[-3000:]}"
    assert "current" in res.stdout


def test_output_is_independent_of_hash_seed(derivations):
    """The PYTHONHASHSEED=12345 derivation is the committed files byte for byte, as the PYTHONHASHSEED=0 one is
    (the check above)."""
    _, files = derivations
    assert {"manifest.json", "sg_kernels.h", "sg_kernels.cdef", "sg_needle_bar.c", "sg_take_up.c",
            "sg_hook_drive.c"} <= set(files)
    committed = {p.name: p.read_text() for p in _committed_generated()}
    assert set(committed) == set(files)
    assert [n for n in sorted(files) if files[n] != committed[n]] == []


def test_check_fails_on_stale_or_missing_files(derivations, tmp_path):
    _, files = derivations
    out = _copy_committed(tmp_path / "generated")
    target = out / "sg_needle_bar.c"
    target.write_text(target.read_text(encoding="utf-8").replace("Total ops", "Total opz", 1), encoding="utf-8")
    (out / "sg_take_up.c").unlink()
    report = io.StringIO()
    assert check(files, out, report) is False
    assert "sg_needle_bar.c" in report.getvalue() and "Total opz" in report.getvalue()
    assert "sg_take_up.c" in report.getvalue()


def test_check_reports_foreign_files_without_crashing(derivations, tmp_path):
    """A build artifact (an object file of an in-place build) in the output folder is not derive's business;
    an unreadable file it would write is reported as a difference, not a traceback."""
    _, files = derivations
    out = _copy_committed(tmp_path / "generated")
    (out / "sg_needle_bar.o").write_bytes(b"\x7fELF\x02\x01\x01\x00" + bytes(range(256)))
    assert check(files, out, io.StringIO()) is True
    (out / "sg_take_up.c").write_bytes(b"\xff\xfe not utf-8")
    report = io.StringIO()
    assert check(files, out, report) is False
    assert "sg_take_up.c" in report.getvalue()


# -- compiles cleanly ------------------------------------------------------------------------------------------------

def _compile(src: Path, obj: Path, includes=(CSRC, GENERATED)):
    cmd = [GCC, *CFLAGS, *(f"-I{d}" for d in includes), "-c", str(src), "-o", str(obj)]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, f"{' '.join(cmd)}\n{res.stderr[-5000:]}"
    assert res.stderr.strip() == "", res.stderr  # not even a note
    return obj


C_SOURCES = [CSRC / "sg_runtime.c"] + _kernel_files()


@pytest.mark.skipif(GCC is None, reason="gcc not installed")
@pytest.mark.parametrize("src", C_SOURCES, ids=lambda p: p.name)
def test_compiles_without_warnings(src, tmp_path):
    _compile(src, tmp_path / (src.stem + ".o"))


@pytest.mark.skipif(GCC is None, reason="gcc not installed")
@pytest.mark.parametrize("closed_form", [True, False], ids=["closed", "newton_only"])
def test_user_mechanism_compiles_without_warnings(tmp_path, closed_form):
    """A declaration outside the catalog, with a slider on a moving link, rendered and compiled alone."""
    from sewgen.derive import Mechanism, generate, render_files

    m = Mechanism("codegen_probe", "crank pin in a block on an oscillating guide bar, the bar driving a rod")
    r = m.length("crank", "10 mm", "crank")
    l = m.length("rod", "40 mm", "rod")
    oy = m.length("guide_pivot_y", "-50 mm", "guide pivot", signed=True)
    crank = m.driven("crank", pivot=m.ground.at(0, 0))
    guide = m.link("guide", guess="-90 deg")
    block = m.slider("block", guide=guide.line(at=(0, 0), angle=0), guess="50 mm")
    rod = m.link("rod", guess="0 deg")
    bar = m.slider("bar", guide=m.ground.line(at=(0, -0.08), angle=0), guess="0 mm")
    m.revolute(m.ground.at(0, oy), guide.at(0, 0), name="O")
    m.revolute(crank.at(r, 0), block.at(0, 0), name="B")
    m.revolute(guide.at(0.07, 0), rod.at(0, 0), name="E")
    m.revolute(rod.at(l, 0), bar.at(0, 0), name="C")
    m.point("pin", bar.at(0, 0))
    files = render_files([generate(m, closed_form=closed_form)])
    for name, text in files.items():
        (tmp_path / name).write_text(text, encoding="utf-8")
    _compile(tmp_path / "sg_codegen_probe.c", tmp_path / "probe.o", includes=(CSRC, tmp_path))


USER_TEXTS = {
    "quotes_backslashes_unicode": ('Crank "A" \\ slider \\n 针杆 — ends in a backslash \\', 'radius "r" \\'),
    "comment_terminator_in_title": ("A slider-crank */ with a comment terminator in its title", "crank radius"),
    "trigraph_in_parameter_doc": ("A slider-crank", "crank radius (really??!)"),
    "trigraph_before_quote": ("A slider-crank", 'crank radius ??/"'),
}


@pytest.mark.skipif(GCC is None, reason="gcc not installed")
@pytest.mark.parametrize("case", list(USER_TEXTS))
def test_user_text_cannot_break_the_generated_c(tmp_path, case):
    """Docstrings are free text; the C they are copied into (comments, the manifest string) must still
    compile with the project's flags, and the manifest must round-trip."""
    from sewgen.derive import Mechanism, generate, render_files

    doc, pdoc = USER_TEXTS[case]
    m = Mechanism("text_probe", doc)
    r = m.length("crank", "10 mm", pdoc)
    crank = m.driven("crank", pivot=m.ground.at(0, 0))
    rod = m.link("rod", guess="-30 deg")
    bar = m.slider("bar", guide=m.ground.line(at=(0, 0), angle=0), guess="40 mm")
    m.revolute(crank.at(r, 0), rod.at(0, 0), name="B")
    m.revolute(rod.at(0.04, 0), bar.at(0, 0), name="C")
    gen = generate(m)
    assert gen.manifest["doc"] == doc.strip()
    assert gen.manifest["params"][0]["doc"] == pdoc
    for name, text in render_files([gen]).items():
        (tmp_path / name).write_text(text, encoding="utf-8")
    _compile(tmp_path / "sg_text_probe.c", tmp_path / "probe.o", includes=(CSRC, tmp_path))


# -- self-describing -------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("path", _kernel_files(), ids=lambda p: p.name)
def test_kernel_preamble_and_op_counts(path):
    text = path.read_text(encoding="utf-8")
    name = path.stem[len("sg_"):]
    first = text.split("*/", 1)[0]
    assert text.startswith("/*") and "do not edit" in first.lower()
    assert name in first
    manifest = _manifest()[name]
    kernels = manifest["kernels"]
    expected = {f"sg_{name}_{k}" for k in ("constants", "residual", "lu_factor", "lu_solve", "scales", "blocks",
                                             "motion", "rates", "observe", "forces", "force_matrix", "anchors")}
    if manifest["closed_form"]:
        expected.add(f"sg_{name}_closed")
    assert set(kernels) == expected
    counted = dict(re.findall(r"/\* (sg_\w+) -- Total ops: (\d+) \*/", text))
    assert set(counted) == expected
    for kernel, info in kernels.items():
        assert int(counted[kernel]) == info["ops"] > 0
        # the count sits right above the kernel's definition
        assert re.search(rf"/\* {kernel} -- Total ops: \d+ \*/\n(void|int) {kernel}\(", text), kernel


@pytest.mark.parametrize("name", ["sg_kernels.h", "sg_kernels.cdef"])
def test_header_and_cdef_preamble(name):
    first = (GENERATED / name).read_text(encoding="utf-8").split("*/", 1)[0]
    assert "do not edit" in first.lower()


# -- the C namespace -------------------------------------------------------------------------------------------------

C_KEYWORDS = {
    "auto", "break", "case", "char", "const", "continue", "default", "do", "double", "else", "enum", "extern",
    "float", "for", "goto", "if", "inline", "int", "long", "register", "restrict", "return", "short", "signed",
    "sizeof", "static", "struct", "switch", "typedef", "union", "unsigned", "void", "volatile", "while",
    "size_t", "_Bool",
}


def _code_tokens(text: str) -> list[str]:
    """The C text with comments, string and character literals and preprocessor lines removed, as tokens."""
    out, i, n = [], 0, len(text)
    line_start = True
    while i < n:
        ch = text[i]
        if line_start and ch == "#":  # a preprocessor line (with continuations)
            while i < n and (text[i] != "\n" or text[i - 1] == "\\"):
                i += 1
            continue
        if text.startswith("/*", i):
            j = text.find("*/", i + 2)
            assert j >= 0, "unterminated comment"
            i = j + 2
            out.append(" ")
            continue
        if text.startswith("//", i):
            while i < n and text[i] != "\n":
                i += 1
            continue
        if ch in "\"'":
            j = i + 1
            while j < n and text[j] != ch:
                j += 2 if text[j] == "\\" else 1
            assert j < n, "unterminated literal"
            i = j + 1
            out.append(" ")
            continue
        if ch == "\n":
            line_start = True
        elif not ch.isspace():
            line_start = False
        out.append(ch)
        i += 1
    return re.findall(r"[A-Za-z_]\w*|\d[\w.]*|\S", "".join(out))


def _file_scope_names(tokens: list[str]) -> list[tuple[str, bool]]:
    """(name, static) of what each file-scope declaration or definition declares: the identifier right
    before the first '(', '[', '=' or ';' of the declaration outside parentheses and braces."""
    names, brace, paren = [], 0, 0
    decl: list[str] = []
    done = False
    for tok in tokens:
        if tok == "{":
            brace += 1
        elif tok == "}":
            brace -= 1
            if brace == 0 and paren == 0:
                decl, done = [], False  # end of a function body (or of a struct / initializer)
            continue
        if brace:
            continue
        if tok == "(":
            if paren == 0 and not done and decl and decl[-1] not in C_KEYWORDS and re.match(r"[A-Za-z_]", decl[-1]):
                names.append((decl[-1], "static" in decl))
                done = True
            paren += 1
        elif tok == ")":
            paren -= 1
        elif paren:
            continue
        elif tok in ("[", "=", ";", ","):
            if not done and decl and decl[-1] not in C_KEYWORDS and re.match(r"[A-Za-z_]", decl[-1]):
                names.append((decl[-1], "static" in decl))
            done = tok in ("[", "=")
            if tok == ";":
                decl, done = [], False
            elif tok == ",":
                done = False
        else:
            decl.append(tok)
    return names


def test_file_scope_name_finder_works():
    toks = _code_tokens('/* c */ int sg_a(int x);\nstatic double helper(void) { return 1.0; }\n'
                        'static const unsigned char sg_b[2] = { 1, 0 };\nconst char *sg_c(void) { return "x(y"; }\n'
                        'typedef struct sg_d { int a; } sg_d;\n#define FOO 1\nint bad_name = 3;\n')
    assert _file_scope_names(toks) == [("sg_a", False), ("helper", True), ("sg_b", True), ("sg_c", False),
                                       ("sg_d", False), ("bad_name", False)]


def _defines(text: str) -> list[str]:
    return re.findall(r"^\s*#\s*define\s+(\w+)", text, flags=re.M)


@pytest.mark.parametrize("path", _kernel_files() + [GENERATED / "sg_kernels.h", CSRC / "sg_runtime.h"],
                         ids=lambda p: p.name)
def test_every_file_scope_name_is_prefixed(path):
    """Generated code and the runtime header put only sg_ names (SG_ macros) into the includer's namespace."""
    text = path.read_text(encoding="utf-8")
    names = _file_scope_names(_code_tokens(text))
    assert names, "found no declarations: the scanner is broken"
    bad = [n for n, _ in names if not n.startswith("sg_")]
    assert not bad, f"{path.name}: file-scope names without the sg_ prefix: {bad}"
    bad_macros = [d for d in _defines(text) if not d.startswith("SG_")]
    assert not bad_macros, f"{path.name}: macros without the SG_ prefix: {bad_macros}"


def test_runtime_exports_only_prefixed_names():
    text = (CSRC / "sg_runtime.c").read_text(encoding="utf-8")
    exported = [n for n, static in _file_scope_names(_code_tokens(text)) if not static]
    assert "sg_sweep" in exported
    assert [n for n in exported if not n.startswith("sg_")] == []


@pytest.mark.skipif(GCC is None or NM is None, reason="gcc or nm not installed")
def test_object_files_define_only_prefixed_globals(tmp_path):
    for src in C_SOURCES:
        obj = _compile(src, tmp_path / (src.stem + ".o"))
        res = subprocess.run([NM, "-g", "--defined-only", str(obj)], capture_output=True, text=True)
        assert res.returncode == 0, res.stderr
        symbols = [line.split()[-1] for line in res.stdout.splitlines() if line.strip()]
        assert symbols, f"{src.name}: no global symbols?"
        assert [s for s in symbols if not s.startswith("sg_")] == [], src.name


def _user_names(manifest: dict) -> set[str]:
    """Names a user chose: parameters, points, moving bodies, coordinates (their identifier parts)."""
    names = set()
    for key in ("params", "points", "bodies", "coords"):
        for entry in manifest[key]:
            names.update(part for part in entry["name"].split(".") if re.fullmatch(r"[A-Za-z_]\w*", part))
    # generic parts of compound names that the code may legitimately use as C names
    return names - {"angle", "travel", "mass", "inertia", "com_u", "com_v", "phase"}


@pytest.mark.parametrize("path", _kernel_files(), ids=lambda p: p.name)
def test_no_user_names_in_c_code(path):
    """User names appear in comments and in the manifest string only, never as C identifiers."""
    name = path.stem[len("sg_"):]
    users = _user_names(_manifest()[name])
    assert len(users) >= 5  # the scan sees the mechanism's body, joint and point names
    text = path.read_text(encoding="utf-8")
    tokens = _code_tokens(text)
    idents = {t for t in tokens if re.fullmatch(r"[A-Za-z_]\w*", t)}
    assert not (idents & users), f"{path.name}: user names used as C identifiers: {sorted(idents & users)}"
    assert f"sg_{name}_motion" in idents  # the scan does see the code


def test_needle_eye_only_in_comments_and_manifest():
    text = (GENERATED / "sg_needle_bar.c").read_text(encoding="utf-8")
    assert "needle_eye" in text  # it is in the manifest string
    assert "needle_eye" not in _code_tokens(text)
    assert "crank" not in _code_tokens(text)
