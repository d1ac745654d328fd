"""The one exception the command line turns into a one-line message."""


class MocapError(Exception):
    """Bad input or an impossible request, described in one line for the user."""
