"""Text laid out once per distinct string in matplotlib's PDF backend (issue 37).

matplotlib's PDF renderer lays out every line of text it draws (libraqm shaping, then a glyph
load per character: ≈ 0.15 ms a line plus ≈ 12 µs a glyph on this machine), even when the same
string at the same size was laid out a moment before. plan.pdf's camera schedule repeats most
of its cells ('2.90', '30.0', 'wide', the lens, 'new', ...), so within :func:`pdf_layout_cache`
each distinct (string, font, size) is laid out once and its glyph positions reused: the same
glyphs at the same places, the same bytes (tests/outputs/test_pdf_text.py).

The memo sits only in matplotlib.backends.backend_pdf (its module name ``_text_helpers`` points
to a shim for the block); PostScript, SVG, Agg and TextPath lay text out as before. One block
at a time across threads (a re-entrant lock, new in a forked child): the PDF writer holds the
GIL anyway.
"""

from __future__ import annotations

import contextlib
import os
import threading
from collections.abc import Iterator

_LOCK = threading.RLock()
_ACTIVE: list = []  # the memo of the block in progress (nested blocks reuse it)


def _new_lock_in_child() -> None:
    """A forked child (plan.pdf's: camplace.outputs.background) never inherits a held lock."""
    global _LOCK
    _LOCK = threading.RLock()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_new_lock_in_child)


class _LayoutMemo:
    """Stands in for matplotlib._text_helpers inside backend_pdf: ``layout`` memoised by
    (string, font, size in pt, features, language); everything else passed through."""

    def __init__(self, helpers, renderer_cls) -> None:
        self._helpers, self._get_font = helpers, renderer_cls._get_font_ttf
        self.size: dict[int, float] = {}  # id(font) -> the size (pt) it was last set to for the PDF
        self.memo: dict[tuple, tuple] = {}  # key -> (font kept alive, its layout items)

    def __getattr__(self, name: str):
        return getattr(self._helpers, name)

    def get_font_ttf(self, renderer, prop):
        """RendererPdf._get_font_ttf, noting the size the font is set to (pt)."""
        font = self._get_font(renderer, prop)
        self.size[id(font)] = prop.get_size_in_points()
        return font

    def layout(self, string: str, font, *, features=None, language=None) -> list:
        """matplotlib._text_helpers.layout's items (a list), laid out once per key."""
        key = (string, id(font), self.size.get(id(font)), features, language)
        hit = self.memo.get(key)
        if hit is None:
            hit = self.memo[key] = (font, list(self._helpers.layout(string, font, features=features,
                                                                    language=language)))
        return hit[1]


def _has_internals(backend_pdf) -> bool:
    """Whether this matplotlib's PDF backend has the two internals the memo stands in for
    (its module ``_text_helpers`` with ``layout``, and ``RendererPdf._get_font_ttf``: as in
    matplotlib 3.11)."""
    helpers = getattr(backend_pdf, "_text_helpers", None)
    return callable(getattr(helpers, "layout", None)) and callable(
        getattr(backend_pdf.RendererPdf, "_get_font_ttf", None))


@contextlib.contextmanager
def pdf_layout_cache() -> Iterator[_LayoutMemo | None]:
    """Within the block, matplotlib's PDF backend lays out each distinct string once; yields the
    memo (``.memo``: one entry per layout made), or None on a matplotlib without the internals
    it stands in for (nothing changed: the text is laid out as matplotlib does). Nested blocks
    share the outer one's memo; other threads' blocks wait."""
    from matplotlib.backends import backend_pdf

    with _LOCK:
        if _ACTIVE:
            yield _ACTIVE[0]
            return
        if not _has_internals(backend_pdf):  # another matplotlib: every string laid out as before
            yield None
            return
        renderer = backend_pdf.RendererPdf
        shim = _LayoutMemo(backend_pdf._text_helpers, renderer)
        had_own = "_get_font_ttf" in renderer.__dict__
        own = renderer.__dict__.get("_get_font_ttf")
        backend_pdf._text_helpers = shim
        renderer._get_font_ttf = lambda self, prop: shim.get_font_ttf(self, prop)
        _ACTIVE.append(shim)
        try:
            yield shim
        finally:
            _ACTIVE.clear()
            backend_pdf._text_helpers = shim._helpers
            if had_own:
                renderer._get_font_ttf = own
            else:
                del renderer._get_font_ttf
