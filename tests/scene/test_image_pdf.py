"""PDF floor plans and scales (issue 25): a PDF page is rendered (PDFium) and read
as a plan image; '1:N' turns into metres per pixel through the page's size on paper, or
through the DPI a raster file records; what cannot be used says so in one line."""

from __future__ import annotations

import pytest
from PIL import Image

from camplace.core.errors import InputError
from camplace.scene.importers import read_plan
from camplace.scene.importers.image_read import drawing_ratio
from tests.scene.image_drawings import PX, ROOMS, draw_line_plan, room_area

DPI = 127  # 0.2 mm of paper per pixel: the 0.02 m pixels of the drawing are 1:100


@pytest.fixture(scope="module")
def drawn(tmp_path_factory):
    """(png path, pdf path, what the PNG gives at its scale): the hairline plan and the
    same pixels as a one-page PDF at 1:100."""
    folder = tmp_path_factory.mktemp("pdf")
    sheet = draw_line_plan(folder / "plan.png")
    with Image.open(sheet.path) as im:
        im.convert("RGB").save(folder / "plan.pdf", resolution=DPI)
        im.save(folder / "plan-dpi.png", dpi=(DPI, DPI))
    return sheet.path, folder / "plan.pdf", read_plan(sheet.path, scale=PX, ocr=False)


def _areas(got) -> list[float]:
    from shapely.geometry import Polygon

    return sorted(Polygon(z["polygon"]).area for z in got.scene["zones"])


def test_a_pdf_page_at_its_drawing_scale(drawn):
    _, pdf, png = drawn
    got = read_plan(pdf, scale="1:100", ocr=False)  # rendered at 0.01 m/px: twice the PNG's pixels
    assert got.used["scale"] == "0.01 m/px (1:100 at 254 dpi; page 1 of 1, rendered at 254 dpi)"
    assert _areas(got) == pytest.approx(sorted(room_area(n) for n in ROOMS), rel=0.15)
    assert len(_areas(got)) == len(_areas(png))


def test_a_raster_file_at_its_recorded_dpi(drawn):
    png, _, ref = drawn
    got = read_plan(png.with_name("plan-dpi.png"), scale="1:100", ocr=False)
    assert float(got.used["scale"].split()[0]) == pytest.approx(PX, rel=1e-3)
    assert _areas(got) == pytest.approx(_areas(ref), rel=1e-6)


@pytest.mark.parametrize("name, options, option, words", [
    ("plan.pdf", {"scale": 0.02}, "scale", "is a PDF, whose pixels are rendered here"),
    ("plan.pdf", {"scale": "1:100", "page": 2}, "page", "has 1 page; expected 1..1, got 2"),
    ("plan.pdf", {"scale": "1:100", "page": 0}, "page", "has 1 page; expected 1..1, got 0"),
    ("plan.png", {"scale": 0.02, "ref": (0, 0, 10, 0, 1.0)}, "ref", "not both"),
    ("plan.png", {"scale": "1:100"}, "scale", "does not record its resolution (dpi)"),
    ("plan.png", {"scale": 0.02, "page": 1}, "page", "is an image, not a PDF"),
    ("plan.png", {"scale": "1:x"}, "scale", "expected metres per pixel (e.g. 0.02) or a drawing scale 1:N"),
])
def test_what_cannot_be_used_says_so(drawn, name, options, option, words):
    png, _, _ = drawn
    with pytest.raises(InputError) as err:
        read_plan(png.with_name(name), ocr=False, **options)
    assert err.value.option == option and words in str(err.value)


def test_a_damaged_pdf_is_one_line(tmp_path):
    bad = tmp_path / "plan.pdf"
    bad.write_bytes(b"%PDF-1.7\nnot really\n")
    with pytest.raises(InputError, match=r"plan\.pdf: not a readable PDF"):
        read_plan(bad, scale="1:100")


@pytest.mark.parametrize("text, ratio", [("1:100", 100.0), (" 1 / 50 ", 50.0), ("1:62.5", 62.5), ("0.02", None),
                                         (0.02, None), (None, None)])
def test_drawing_ratio(text, ratio):
    assert drawing_ratio(text) == ratio


@pytest.mark.parametrize("paper", [(0, 0, 0), (20, 60, 170)])  # a dark-mode screenshot, a blueprint
def test_light_lines_on_dark_paper_are_read_inverted(drawn, tmp_path, paper):
    import numpy as np

    png, _, ref = drawn
    with Image.open(png) as im:
        a = np.asarray(im.convert("L"), np.float32)[..., None] / 255.0
    ink = np.array([255, 255, 255], np.float32)  # white lines
    Image.fromarray((a * np.array(paper, np.float32) + (1 - a) * ink).astype(np.uint8)).save(tmp_path / "dark.png")
    got = read_plan(tmp_path / "dark.png", scale=PX, ocr=False)
    assert got.used["scale"].endswith("light lines on dark paper, read inverted)")
    assert _areas(got) == pytest.approx(_areas(ref), rel=0.02)


@pytest.mark.parametrize("text, metres", [("10700", 10.7), ("3.90", 3.9), ("10,70", 10.7), ("12'-6\"", 3.81),
                                          ("12’ 6”", 3.81), ("8'", 2.4384), ("3'-0 1/2\"", 0.9271),
                                          ("12'-13\"", None), ("Kitchen", None), ("42", None)])
def test_dimension_texts(text, metres):
    """Millimetres, metres with decimals, and US feet-inches as OCR reads them."""
    from camplace.scene.importers.image_scale import dimension_value_m

    got = dimension_value_m(text)
    assert got == (None if metres is None else pytest.approx(metres, abs=1e-4))


@pytest.mark.parametrize("suffix", [".webp", ".bmp", ".gif"])
def test_other_raster_formats(drawn, tmp_path, suffix):
    """WebP (web listings), BMP and GIF plans read as PNG does."""
    png, _, ref = drawn
    with Image.open(png) as im:
        im.convert("RGB").save(tmp_path / f"plan{suffix}", **({"lossless": True} if suffix == ".webp" else {}))
    got = read_plan(tmp_path / f"plan{suffix}", scale=PX, ocr=False)
    assert _areas(got) == pytest.approx(_areas(ref), rel=1e-6)
