"""The one error type the command line turns into a one-line message and a non-zero exit."""


class ForaNavError(Exception):
    """A user-facing failure: bad input file, bad argument, missing model.

    The message is printed as a single line by ``foranav``; keep it short and name the file and field.
    """
