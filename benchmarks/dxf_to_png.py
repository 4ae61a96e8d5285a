"""Draw a DXF floor plan as a plan image at a known scale, to try the image importer on
plans drawn by another tool (ezdxf's drawing add-on, matplotlib backend, black on white).

    python benchmarks/dxf_to_png.py PLAN.dxf OUT.png --unit-m 0.01 --scale 0.02
    camplace scene import OUT.png --scale 0.02 --out x.yaml

``--unit-m``: metres per drawing unit (0.01 for a drawing in cm); ``--scale``: metres per
pixel of the image. 5 % of paper is left around the drawing's extents.
"""

from __future__ import annotations

import argparse


def draw(src: str, out: str, unit_m: float, m_per_px: float) -> tuple[int, int]:
    """Write ``out`` (PNG) and return its (width, height) in pixels."""
    import ezdxf
    import matplotlib
    from ezdxf import bbox
    from ezdxf.addons.drawing import Frontend, RenderContext
    from ezdxf.addons.drawing.config import BackgroundPolicy, ColorPolicy, Configuration
    from ezdxf.addons.drawing.matplotlib import MatplotlibBackend

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    doc = ezdxf.readfile(src)
    msp = doc.modelspace()
    ext = bbox.extents(msp, fast=True)
    pad = 0.05 * max(ext.size.x, ext.size.y)
    x0, y0 = ext.extmin.x - pad, ext.extmin.y - pad
    w, h = ext.size.x + 2 * pad, ext.size.y + 2 * pad
    dpi = 100
    wpx, hpx = w * unit_m / m_per_px, h * unit_m / m_per_px
    fig = plt.figure(figsize=(wpx / dpi, hpx / dpi), dpi=dpi)
    ax = fig.add_axes((0, 0, 1, 1))
    config = Configuration(background_policy=BackgroundPolicy.WHITE, color_policy=ColorPolicy.BLACK)
    Frontend(RenderContext(doc), MatplotlibBackend(ax), config=config).draw_layout(msp, finalize=False)
    ax.set_xlim(x0, x0 + w)
    ax.set_ylim(y0, y0 + h)
    ax.axis("off")
    fig.savefig(out, dpi=dpi, facecolor="white")
    plt.close(fig)
    return round(wpx), round(hpx)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dxf")
    ap.add_argument("png")
    ap.add_argument("--unit-m", type=float, default=1.0, help="metres per drawing unit")
    ap.add_argument("--scale", type=float, default=0.02, help="metres per pixel of the image")
    a = ap.parse_args()
    print(a.png, *draw(a.dxf, a.png, a.unit_m, a.scale))


if __name__ == "__main__":
    main()
