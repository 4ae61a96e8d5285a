"""camplace.outputs.pdf_text: each string laid out once in matplotlib's PDF backend, same bytes."""

from __future__ import annotations

import io

import pytest
from hypothesis import given, settings, strategies as st

from camplace.outputs.pdf_text import pdf_layout_cache


def _pdf(lines: list[tuple[str, float]], cached: bool) -> tuple[bytes, int]:
    """A one-page PDF of ``lines`` (text, size pt), one multi-line column of them too; the
    bytes and the number of layouts made (-1 without the cache)."""
    from matplotlib.backends.backend_pdf import PdfPages
    from matplotlib.figure import Figure

    fig = Figure(figsize=(4, 4))
    for k, (s, size) in enumerate(lines):
        fig.text(0.05, 0.95 - 0.05 * k, s, fontsize=size, va="top")
    fig.text(0.6, 0.95, "\n".join(s for s, _ in lines), fontsize=6, va="top", linespacing=1.6)
    buf = io.BytesIO()
    with pdf_layout_cache() if cached else _nothing() as memo:
        with PdfPages(buf, metadata={"CreationDate": None}) as pages:
            fig.savefig(pages, format="pdf")
        made = len(memo.memo) if cached else -1
    return buf.getvalue(), made


class _nothing:
    def __enter__(self):
        return None

    def __exit__(self, *exc):
        return False


def test_same_bytes_and_one_layout_per_string_and_size():
    # 'wide' at 6 pt four times and at 9 pt once: the 9 pt one must not reuse the 6 pt glyph places
    lines = [("wide", 6.0)] * 4 + [("wide", 9.0), ("2.90", 6.0), ("2.90", 6.0), ("\u0393 \u2265 3 \u2013 yaw (\u00b0)", 6.0)]
    plain, _ = _pdf(lines, cached=False)
    cached, made = _pdf(lines, cached=True)
    assert cached == plain
    # distinct (string, size): wide@6, wide@9, 2.90@6, the symbols@6 (the column repeats them at 6 pt)
    assert made == 4


@settings(max_examples=12, deadline=None)
@given(st.lists(st.tuples(st.text(alphabet="aW.0179 (m)/\u0393\u00b0\u2013", min_size=1, max_size=12),
                          st.sampled_from([4.2, 6.0, 6.5, 11.0])), min_size=1, max_size=8))
def test_any_strings_give_the_same_bytes(lines):
    assert _pdf(lines, cached=True)[0] == _pdf(lines, cached=False)[0]


def test_backend_restored_after_the_block_even_on_error_and_nested_blocks_share_one_memo():
    from matplotlib import _text_helpers
    from matplotlib.backends import backend_pdf

    with pytest.raises(RuntimeError):
        with pdf_layout_cache() as outer:
            assert backend_pdf._text_helpers is outer and "_get_font_ttf" in backend_pdf.RendererPdf.__dict__
            with pdf_layout_cache() as inner:
                assert inner is outer
            assert backend_pdf._text_helpers is outer  # the inner block leaves the outer one's memo in place
            raise RuntimeError("stop")
    assert backend_pdf._text_helpers is _text_helpers
    assert "_get_font_ttf" not in backend_pdf.RendererPdf.__dict__


@pytest.mark.skipif(not hasattr(__import__("os"), "fork"), reason="no fork on this platform")
def test_a_child_forked_while_another_thread_holds_the_lock_can_take_it():
    import os
    import threading
    import warnings

    from camplace.outputs import pdf_text

    held, release = threading.Event(), threading.Event()

    def hold():
        with pdf_text._LOCK:
            held.set()
            release.wait(5)

    t = threading.Thread(target=hold)
    t.start()
    held.wait(5)
    with warnings.catch_warnings():  # Python 3.12+ warns about fork with threads
        warnings.simplefilter("ignore", DeprecationWarning)
        pid = os.fork()
    if pid == 0:
        os._exit(0 if pdf_text._LOCK.acquire(timeout=2) else 1)
    _, status = os.waitpid(pid, 0)
    release.set()
    t.join()
    assert os.waitstatus_to_exitcode(status) == 0


def test_a_matplotlib_without_the_internals_is_left_as_it_is(monkeypatch):
    """Where backend_pdf's _text_helpers has no layout() (another matplotlib), the block yields
    None and patches nothing: the text is laid out as that matplotlib does."""
    from matplotlib.backends import backend_pdf

    other = object()
    monkeypatch.setattr(backend_pdf, "_text_helpers", other)
    before = backend_pdf.RendererPdf._get_font_ttf
    with pdf_layout_cache() as memo:
        assert memo is None
        assert backend_pdf._text_helpers is other and backend_pdf.RendererPdf._get_font_ttf is before
    assert backend_pdf._text_helpers is other
