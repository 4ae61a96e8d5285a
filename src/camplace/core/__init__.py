"""camplace.core: what every stage shares - errors (CamplaceError, InputError with the
parameter it is about), files (atomic writes), memory (the one memory limit and its error)."""
