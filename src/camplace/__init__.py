"""camplace: choose where to mount cameras so every place gets the coverage it needs.

The pipeline (see docs/design.md): scene -> targets -> candidates -> visibility ->
problem -> solvers -> metrics -> report. ``camplace.pipeline.run`` chains them.
"""

from camplace.errors import CamplaceError, InputError

__version__ = "0.1.0"
__all__ = ["CamplaceError", "InputError", "__version__"]
