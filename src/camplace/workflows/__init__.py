"""camplace.workflows (layer 11): the stages chained - run (``prepare``, ``run``), evaluate,
solve (saved instances), bench, compare, render, essential, scan (synthetic scans), sites
(privacy zones, existing cameras), storeys."""
