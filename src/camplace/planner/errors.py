"""The planner's request errors: one line naming the field, and the HTTP status to answer with."""

from __future__ import annotations

from camplace.core.errors import InputError


class ApiError(InputError):
    """A refused request: ``status`` (4xx), ``field`` (the body key, path part or query
    parameter at fault) and a one-line message saying what was expected."""

    def __init__(self, message: str, field: str, status: int = 400) -> None:
        super().__init__(message, option=field)
        self.field = field
        self.status = int(status)

    def payload(self) -> dict:
        """The JSON body of the error answer."""
        return {"error": str(self), "field": self.field}
