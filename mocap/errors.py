"""The error and warning the command line prints as one line."""


class MocapError(Exception):
    """Bad input or an impossible request, described in one line for the user."""


class MocapWarning(UserWarning):
    """Input that is usable in part (a truncated video), said in one line; work goes on."""
