"""The background warm-up of a fresh install (camplace.workflows.warm): started only on a
cold cache, stopped by the run, and it runs every stage after visibility."""

from __future__ import annotations

import camplace.workflows.warm as warm


def test_started_only_on_a_cold_cache_and_stopped(monkeypatch):
    monkeypatch.setattr(warm, "cache_is_cold", lambda: False)
    assert warm.start("greedy") is None
    monkeypatch.setattr(warm, "cache_is_cold", lambda: True)
    proc = warm.start("greedy")
    assert proc is not None and proc.poll() is None
    warm.stop(proc)
    assert proc.poll() is not None
    warm.stop(None)


def test_the_warm_up_runs_the_stages_after_visibility(tmp_path, monkeypatch):
    written = []
    import camplace.outputs.write as write

    real = write.write_outputs

    def spy(out, *args, **kwargs):
        paths = real(out, *args, **kwargs)
        written.extend(paths)
        return paths

    monkeypatch.setattr(write, "write_outputs", spy)
    warm.warm("greedy")
    assert {"placement.json", "report.html", "plan.pdf"} <= set(written)  # the solver, the report and the plan set
