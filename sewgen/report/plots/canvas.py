"""The Agg canvas every figure draws on: matplotlib's own, except that plain text is drawn from whole-string
bitmaps kept in a cache.

Why: matplotlib 3.11 renders text glyph by glyph from Python (shaping, then one FreeType render and one blit per
glyph, ~0.1 ms a glyph), so text was about a quarter of ``sewgen analyze``'s plotting time (≈ 11,000 glyphs over
the nine figures and the GIF) — measured with cProfile on JB1-3. FreeType draws a whole string into one bitmap in
one C call (``FT2Font.set_text`` + ``draw_glyphs_to_bitmap``, the way matplotlib itself drew text before 3.11),
and the same strings recur (tick labels, axis labels, the GIF's readouts): each (string, font, size, dpi,
hinting, antialiasing) is rendered once per process and blitted as an image (``draw_image``) in the text's
colour. A string is placed at whole pixels (its glyphs keep their relative sub-pixel positions), which can move
it by up to half a pixel against matplotlib's own placement.

Measures of plain strings (``get_text_width_height_descent``) are kept per process in the same way.

Both are also kept on disk between runs (:func:`load`, :func:`save`: ``$SEWGEN_CACHE/text``, one file per
matplotlib, FreeType and font set-up): shaping a string costs matplotlib 3.11 40–60 µs a glyph (libraqm and
FreeType's hinter, no glyph cache), so the strings of a first ``sewgen analyze`` took ~0.8 s of CPU per process;
a later run renders only the strings it has not met before. A key names the font file the string is drawn in,
never a per-process hash.

Math text (``$...$``), text at angles other than 0° and 90°, and text with font features or a language set
are left to matplotlib.
"""
from __future__ import annotations

import os
import pickle
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg, RendererAgg, get_hinting_flag
from matplotlib.font_manager import findfont
from sewgen.engine.loader import cache_root, locked
from sewgen.errors import SewgenError
from sewgen.files import replacing

#: Rendered strings kept (a figure set uses a few hundred distinct ones).
CACHE_SIZE = 4096
_bitmaps: dict = {}
_extents: dict = {}
_files: dict = {}  # hash(FontProperties) -> _font_file(...), in this process
#: How many of each were loaded from disk (:func:`save` writes only when more are known).
_loaded = (0, 0)
#: Set once the renderer's internals this module uses (``_prepare_font``, FT2Font's whole-string calls) turn
#: out missing or different in the installed matplotlib: every string is then drawn by matplotlib itself.
_unsupported = False


class TextCacheRenderer(RendererAgg):
    """:class:`RendererAgg` drawing plain text from the cache of whole-string bitmaps (see the module)."""

    def draw_text(self, gc, x, y, s, prop, angle, ismath=False, mtext=None):
        global _unsupported
        if _unsupported or ismath or angle not in (0, 90) or not s or _shaped(mtext):
            return super().draw_text(gc, x, y, s, prop, angle, ismath=ismath, mtext=mtext)
        try:
            coverage, dx, dy = self._bitmap(s, prop, gc.get_antialiased())
        except (AttributeError, TypeError):  # a matplotlib whose renderer internals differ: its own text, always
            _unsupported = True
            return super().draw_text(gc, x, y, s, prop, angle, ismath=ismath, mtext=mtext)
        if coverage is None:
            return None
        rgba = gc.get_rgb()
        if len(rgba) == 3 or gc.get_forced_alpha():
            rgba = rgba[:3] + (gc.get_alpha(),)
        h, w = coverage.shape
        # (x, y): the start of the baseline, y measured down from the top; (dx, dy): the bitmap's top left from it
        if angle == 90:  # turned a quarter counter-clockwise about (x, y): (right, down) -> (down, -right)
            coverage = np.rot90(coverage)
            left, top = x + dy, y - dx - w
        else:
            left, top = x + dx, y + dy
        left, top = round(left), round(top)
        img = np.empty(coverage.shape + (4,), np.uint8)
        img[..., :3] = np.round(np.asarray(rgba[:3]) * 255.0).astype(np.uint8)
        img[..., 3] = coverage if rgba[3] >= 1.0 else np.round(coverage * rgba[3]).astype(np.uint8)
        # draw_image takes the rows bottom first and their bottom-left corner measured up from the canvas' bottom
        self.draw_image(gc, left, self.height - top - img.shape[0], np.ascontiguousarray(img[::-1]))
        return None

    def get_text_width_height_descent(self, s, prop, ismath):
        """matplotlib's measure of a string, kept per process (its own cache lives and dies with each figure's
        renderer, and each measure shapes the string anew)."""
        if ismath:
            return super().get_text_width_height_descent(s, prop, ismath)
        key = (s, *_font_file(prop), prop.get_size_in_points(), self.dpi, _hinting())
        hit = _extents.get(key)
        if hit is None:
            hit = super().get_text_width_height_descent(s, prop, ismath)
            if len(_extents) >= CACHE_SIZE:
                _extents.clear()
            _extents[key] = hit
        return hit

    def _bitmap(self, s, prop, antialiased):
        """(coverage (h, w) uint8, dx, dy): the string's bitmap and its top-left corner from the baseline start,
        in pixels (y down); rendered once per distinct key."""
        flags = get_hinting_flag()
        key = (s, *_font_file(prop), prop.get_size_in_points(), self.dpi, bool(antialiased), _hinting())
        hit = _bitmaps.get(key)
        if hit is not None:
            return hit
        font = self._prepare_font(prop)
        font.set_text(s, 0.0, flags=flags)
        font.draw_glyphs_to_bitmap(antialiased=bool(antialiased))
        coverage = np.array(font.get_image(), dtype=np.uint8)
        xo, _yo = font.get_bitmap_offset()
        descent = font.get_descent() / 64.0
        if not coverage.size or not coverage.any():
            hit = (None, 0.0, 0.0)
        else:
            # the bitmap's last row lies one pixel below the descent line; its first column at the ink's left
            hit = (coverage, xo / 64.0, descent - coverage.shape[0] + 1.0)
        if len(_bitmaps) >= CACHE_SIZE:
            _bitmaps.clear()
        _bitmaps[key] = hit
        return hit


def _font_file(prop) -> tuple[str, int]:
    """(path, face index) of the font file ``prop`` is drawn in, as plain values (matplotlib 3.11's ``findfont``
    returns a str subclass that does not unpickle); looked up once a process per font property."""
    key = hash(prop)
    hit = _files.get(key)
    if hit is None:
        found = findfont(prop)
        hit = _files[key] = (str(found), int(getattr(found, "face_index", 0)))
    return hit


def _hinting():
    """matplotlib's hinting flags as a plain value (an enum in matplotlib >= 3.10, an int before): kept in keys
    that are pickled."""
    flags = get_hinting_flag()
    return getattr(flags, "value", flags)


def _cache_file() -> Path | None:
    """The on-disk cache of this matplotlib, FreeType and font set-up, or None where there is no writable
    cache folder."""
    import hashlib

    import matplotlib
    from matplotlib import ft2font, rcParams

    setup = repr((matplotlib.__version__, ft2font.__freetype_version__, getattr(ft2font, "__libraqm_version__", ""),
                  rcParams["text.hinting"], rcParams["text.hinting_factor"], rcParams["text.antialiased"],
                  rcParams["font.family"], rcParams["font.sans-serif"], rcParams["font.monospace"]))
    folder = cache_root() / "text"
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    if not os.access(folder, os.W_OK):
        return None
    return folder / f"{hashlib.sha256(setup.encode()).hexdigest()[:20]}.pickle"


def _read(path: Path) -> tuple[dict, dict]:
    try:
        with open(path, "rb") as fh:
            bitmaps, extents = pickle.load(fh)
        if isinstance(bitmaps, dict) and isinstance(extents, dict):
            return bitmaps, extents
    except Exception:  # noqa: BLE001 - a missing, partly written or foreign file is an empty cache
        pass
    return {}, {}


def load() -> None:
    """Add the strings kept on disk (by earlier runs) to this process's cache."""
    global _loaded
    path = _cache_file()
    if path is None or not path.is_file():
        return
    bitmaps, extents = _read(path)
    for mine, theirs in ((_bitmaps, bitmaps), (_extents, extents)):
        for key, value in theirs.items():
            if len(mine) < CACHE_SIZE:
                mine.setdefault(key, value)
    _loaded = (len(_bitmaps), len(_extents))


def save() -> None:
    """Merge this process's strings into the cache on disk (under a lock; written whole to a temporary file and
    renamed, so a reader never sees half a file); nothing when it knows no string the disk lacks. Never
    raises: the cache only saves time."""
    global _loaded
    if (len(_bitmaps), len(_extents)) == _loaded:
        return
    try:
        path = _cache_file()
        if path is None:
            return
        with locked(path.with_suffix(".lock")):
            bitmaps, extents = _read(path)
            for theirs, mine in ((bitmaps, _bitmaps), (extents, _extents)):
                if len(theirs.keys() | mine.keys()) > CACHE_SIZE:
                    theirs.clear()  # a full cache starts again from this process's strings
                theirs.update(mine)
            with replacing(path) as fh:
                pickle.dump((bitmaps, extents), fh, protocol=pickle.HIGHEST_PROTOCOL)
        _loaded = (len(_bitmaps), len(_extents))
    except (OSError, SewgenError):
        pass


def _shaped(mtext) -> bool:
    """Whether the text asks for font features or a language (matplotlib ≥ 3.10's shaping options)."""
    if mtext is None:
        return False
    features, language = getattr(mtext, "get_fontfeatures", None), getattr(mtext, "get_language", None)
    return bool((features and features()) or (language and language()))


class TextCacheCanvas(FigureCanvasAgg):
    """:class:`FigureCanvasAgg` whose renderer is a :class:`TextCacheRenderer`."""

    def get_renderer(self):
        w, h = self.get_width_height(physical=True)
        key = w, h, self.figure.dpi
        if getattr(self, "_lastKey", None) != key or not isinstance(getattr(self, "renderer", None),
                                                                    TextCacheRenderer):
            self.renderer = TextCacheRenderer(w, h, self.figure.dpi)
            self._lastKey = key
        return self.renderer
