"""The one exception the command line turns into a one-line message, and the warning
it prints as one line before going on."""


class MocapError(Exception):
    """Bad input or an impossible request, described in one line for the user."""


class MocapWarning(UserWarning):
    """Input that is usable in part (a truncated video), said in one line; work goes on."""
