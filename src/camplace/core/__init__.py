"""camplace.core (layer 0): what every stage shares - errors (CamplaceError, InputError with
the parameter it is about), files (atomic writes), memory (the one memory limit and its
error, ``release_pages``), executors (chunked maps in-process, on a process pool or on
Dask), plugins (entry-point registries: the solvers and the visibility engines)."""
