"""The robot layer's error: a valid command whose running failed."""


class BackendError(Exception):
    """The command was valid but running it failed (timeout, no message, process error)."""
