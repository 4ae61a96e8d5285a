"""plan.pdf's bill-of-materials sheet (issue 27): what to buy for the new cameras (the
rows of bom.csv, camplace.outputs.bom), the existing cameras listed apart, the total
price, and the recording load (bandwidth, storage for the retention period)."""

from __future__ import annotations

from camplace.outputs.bom import BOM_COLUMNS, bom_rows
from camplace.outputs.plan_data import PlanData
from camplace.outputs.plan_pdf import MARGIN_MM, RC, _column_table, _figure, _title_block, page_size_mm

BOM_HEAD = ("model", "focal (mm)", "lens", "IR (m)", "count", "unit price", "total")


def _lens_text(model) -> str:
    if model is None or model.lens is None:
        return "\u2013" if model is None else f"{model.model} {model.width}x{model.height}"
    lens = model.lens
    rng = f"{lens.focal_min_mm:g}" if not lens.varifocal else f"{lens.focal_min_mm:g}\u2013{lens.focal_max_mm:g}"
    return f"{model.model} {model.width}x{model.height}, {rng} mm, {lens.pixel_um:.2f} \u00b5m"


def bom_table_rows(data: PlanData, existing: bool = False) -> list[tuple[str, ...]]:
    """BOM_HEAD rows of the new (or existing) cameras: bom.csv's rows with the lens and IR range."""
    by_name = {m.name: m for m in data.models}
    out = []
    for r in bom_rows(data.cameras, data.price, existing):
        m = by_name.get(r.model)
        ir = "\u2013" if m is None or m.ir_range_m is None else f"{m.ir_range_m:g}"
        cells = dict(zip(BOM_COLUMNS, r.cells()))
        out.append((r.model, cells["focal_mm"] or "\u2013", _lens_text(m), ir, cells["count"], cells["unit_price"],
                    cells["total"]))
    return out


def recording_lines(rec: dict | None) -> list[str]:
    """The recording load (placement.json ``recording``) in words."""
    if not rec:
        return ["recording load: no camera type gives a bitrate (bitrate_mbps)"]
    out = [f"recording bandwidth: {rec['bandwidth_new_mbps']:g} Mbit/s new cameras, {rec['bandwidth_mbps']:g} Mbit/s "
           f"all cameras"]
    if "retention_days" in rec:
        out.append(f"storage for {rec['retention_days']:g} days of continuous recording: {rec['storage_new_tb']:.2f} TB "
                   f"new cameras, {rec['storage_tb']:.2f} TB all cameras (decimal TB)")
    if rec.get("cameras_without_bitrate"):
        out.append(f"{rec['cameras_without_bitrate']} camera(s) without a bitrate are not counted")
    return out


def bom_figure(data: PlanData):
    """Sheet 5: the bill of materials."""
    from matplotlib import rc_context

    with rc_context(RC):
        return _bom_figure(data)


def _bom_figure(data: PlanData):
    fig = _figure(data.paper)
    w, h = page_size_mm(data.paper)
    fs = 7.0 if data.paper == "A3" else 5.5
    row_mm = fs * 1.6 * 25.4 / 72.0
    widths = (8, 4, 14, 3, 3, 4, 4)
    new = bom_table_rows(data)
    total = sum(r.total for r in bom_rows(data.cameras, data.price))
    fig.text(MARGIN_MM / w, 1 - 8.0 / h, "bill of materials: the new cameras by model and focal setting (bom.csv)",
             fontsize=11, weight="bold", va="top")
    top = 1 - 18.0 / h
    for title, rows in (("new cameras", new), ("existing cameras (not bought)", bom_table_rows(data, True))):
        if not rows and title.startswith("existing"):
            continue
        fig.text(MARGIN_MM / w, top, title, fontsize=8, weight="bold", va="bottom")
        tall = (len(rows) + 1) * row_mm / h
        ax = fig.add_axes((MARGIN_MM / w, top - tall - 1.5 / h, 0.62, tall))
        ax.set_axis_off()
        _column_table(ax, BOM_HEAD, rows, widths, fs)
        top -= tall + 12.0 / h
    lines = [f"total price of the new cameras: {total:g} ({sum(int(r[4]) for r in new)} cameras)",
             *recording_lines(data.placement.get("recording"))]
    fig.text(MARGIN_MM / w, top, "\n".join(lines), fontsize=8, va="top", linespacing=1.6)
    _title_block(fig, data, data.sheet(5, "bill of materials"))
    return fig
