"""Plan images: the sheet's pixels and its scale.

A raster file (PNG, JPEG, TIFF) is read with Pillow; a PDF page (architects' usual hand-over)
is rendered with PDFium (pypdfium2) at a resolution of our choosing, so its pixels have a
known size on paper. The scale is metres per pixel (``scale`` a number), a drawing scale
``'1:100'`` (needs the pixels' size on paper: a PDF's, or the DPI a raster file records),
two reference points and their distance (``ref``, raster files only), or, with none of
these, read from the dimension lines by the caller. Light lines on dark paper (blueprints,
dark-mode screenshots) are inverted to dark ink on light paper.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from camplace.core.errors import InputError
from camplace.scene.importers.image_pages import open_pdf

MAX_PIXELS = 100_000_000
INCH_M = 0.0254
PDF_DPI = 200  # a PDF page rendered without a drawing scale: text stays readable for OCR
PDF_TARGET_M_PER_PX = 0.01  # with a drawing scale 1:N, a page is rendered at about this many m per pixel ...
PDF_MAX_PIXELS = 40_000_000  # ... but never with more pixels than this
DARK_PAPER = 100  # median luminance below which the paper is dark and the lines light
RATIO_RE = re.compile(r"^\s*1\s*[:/]\s*(\d+(?:\.\d+)?)\s*$")


@dataclass
class SheetImage:
    """The pixels of a plan sheet: ``rgb`` (H, W, 3) uint8, ``dpi`` the pixels per inch on
    paper (None: unknown), ``pdf`` True for a rendered PDF page, ``about`` a line saying
    where the pixels came from ('' for a plain raster file)."""

    rgb: np.ndarray
    dpi: float | None
    pdf: bool = False
    about: str = ""


def drawing_ratio(scale) -> float | None:
    """N of a drawing scale '1:N' (or '1/N'); None when ``scale`` is a number or None."""
    if not isinstance(scale, str):
        return None
    m = RATIO_RE.match(scale)
    if m is None:
        try:
            float(scale)
        except ValueError:
            raise InputError(f"scale: expected metres per pixel (e.g. 0.02) or a drawing scale 1:N (e.g. 1:100), "
                             f"got '{scale}'", option="scale") from None
        return None
    n = float(m.group(1))
    if not n > 0:
        raise InputError(f"scale: expected a drawing scale 1:N with N > 0, got '{scale}'", option="scale")
    return n


def read_sheet(path: Path, page: int | None = None, scale=None) -> SheetImage:
    """The pixels of ``path``: a raster file, or page ``page`` (1-based, default 1) of a PDF
    rendered at PDF_DPI, or, given a drawing scale 1:N, at about PDF_TARGET_M_PER_PX;
    inverted when the paper is dark (dark_paper)."""
    if path.suffix.lower() == ".pdf":
        sheet = _pdf_page(path, 1 if page is None else page, drawing_ratio(scale))
    elif page is not None:
        raise InputError(f"page: {path.name} is an image, not a PDF; it has no pages to choose", option="page")
    else:
        sheet = SheetImage(*read_image(path))
    if dark_paper(sheet.rgb):
        sheet.rgb = 255 - sheet.rgb
        sheet.about = "; ".join(a for a in (sheet.about, "light lines on dark paper, read inverted") if a)
    return sheet


def dark_paper(rgb: np.ndarray) -> bool:
    """True for light lines on dark paper (a blueprint, a dark-mode screenshot): the sheet's
    median luminance (ITU-R 601, 0..255) is below DARK_PAPER."""
    step = max(1, int(math.sqrt(rgb.shape[0] * rgb.shape[1] / 1e6)))  # about a million pixels decide
    sample = rgb[::step, ::step].astype(np.float32)
    return float(np.median(sample @ np.array([0.299, 0.587, 0.114], np.float32))) < DARK_PAPER


def read_image(path: Path) -> tuple[np.ndarray, float | None]:
    """((H, W, 3) uint8 RGB, DPI or None) of an image file: transparency laid on white
    paper, 16-bit and float scans stretched to 0..255; the DPI the file records (PNG pHYs,
    JPEG/TIFF resolution), None when it records none."""
    from PIL import Image, UnidentifiedImageError

    Image.MAX_IMAGE_PIXELS = MAX_PIXELS
    try:
        with Image.open(path) as im:
            im.load()
            dpi = _dpi(im.info.get("dpi"))
            if im.mode in ("I;16", "I;16B", "I;16L", "I", "F"):
                a = np.asarray(im, np.float64)
                lo, hi = np.percentile(a, [0.1, 99.9])
                grey = np.clip((a - lo) * 255.0 / max(hi - lo, 1e-9), 0, 255).astype(np.uint8)
                return np.repeat(grey[..., None], 3, axis=2), dpi
            if im.mode in ("RGBA", "LA", "PA") or (im.mode == "P" and "transparency" in im.info):
                rgba = im.convert("RGBA")
                im = Image.alpha_composite(Image.new("RGBA", rgba.size, (255, 255, 255, 255)), rgba)
            return np.asarray(im.convert("RGB")), dpi
    except (UnidentifiedImageError, OSError, Image.DecompressionBombError, ValueError) as err:
        raise InputError(f"{path}: not a readable image ({str(err).splitlines()[0]})") from None


def _dpi(value) -> float | None:
    """The horizontal DPI Pillow read (a number or an (x, y) pair); None when absent or not
    plausible (many files say 1 or 72 by default: 72 is kept, a real screen resolution)."""
    if value is None:
        return None
    x = value[0] if isinstance(value, (tuple, list)) else value
    try:
        x = float(x)
    except (TypeError, ValueError):
        return None
    return x if 10 <= x <= 10_000 else None


def _pdf_page(path: Path, page: int, ratio: float | None) -> SheetImage:
    """Page ``page`` of a PDF rendered on white paper (PDFium, through pypdfium2)."""
    doc = open_pdf(path)
    try:
        n = len(doc)
        if not isinstance(page, int) or not 1 <= page <= n:
            raise InputError(f"page: {path.name} has {n} page{'s' if n != 1 else ''}; expected 1..{n}, got {page}",
                             option="page")
        pg = doc[page - 1]
        w_pt, h_pt = pg.get_size()
        dpi = float(PDF_DPI) if ratio is None else ratio * INCH_M / PDF_TARGET_M_PER_PX
        dpi = min(dpi, math.sqrt(PDF_MAX_PIXELS / max(w_pt * h_pt / 72.0 ** 2, 1e-9)))
        rgb = np.asarray(pg.render(scale=dpi / 72.0, fill_color=(255, 255, 255, 255)).to_pil().convert("RGB"))
    finally:
        doc.close()
    return SheetImage(rgb, dpi, True, f"page {page} of {n}, rendered at {dpi:.0f} dpi")


def metres_per_pixel(path: Path, sheet: SheetImage, scale, ref) -> tuple[float, str] | None:
    """(m per pixel, where it came from) of ``scale`` (m per pixel, or a drawing scale
    '1:N' with the sheet's DPI) or ``ref``; None when neither is given (the caller reads
    the dimension lines); InputError when they cannot be used."""
    if scale is not None and ref is not None:
        raise InputError("ref: a scale is given too; give the scale or the reference points, not both", option="ref")
    ratio = drawing_ratio(scale)
    if ratio is not None:
        if sheet.dpi is None:
            raise InputError(f"scale: {path.name} does not record its resolution (dpi), so a drawing scale "
                             f"1:{ratio:g} cannot be turned into metres per pixel; give metres per pixel, or ref",
                             option="scale")
        s = ratio * INCH_M / sheet.dpi
        return s, f"1:{ratio:g} at {sheet.dpi:g} dpi"
    if sheet.pdf and (scale is not None or ref is not None):
        key = "scale" if scale is not None else "ref"
        raise InputError(f"{key}: {path.name} is a PDF, whose pixels are rendered here; give its drawing scale "
                         "as scale 1:N (e.g. 1:100), or nothing to read it from the dimension lines", option=key)
    if scale is not None:
        value = float(scale)  # a number, or its text (drawing_ratio checked it reads as one)
        if not value > 0:
            raise InputError(f"scale: expected metres per pixel > 0, got {scale}", option="scale")
        return value, "given"
    if ref is not None:
        x1, y1, x2, y2, dist = (float(v) for v in ref)
        px = math.hypot(x2 - x1, y2 - y1)
        if px <= 0 or not dist > 0:
            raise InputError(f"ref: expected two distinct points and a distance > 0 m, got {list(ref)}", option="ref")
        return dist / px, f"reference: {dist:g} m over {px:.1f} px"
    return None
