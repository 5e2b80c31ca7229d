"""The one exception type for bad input that crosses the project's edge."""


class SinsInputError(ValueError):
    """Bad input from a user: a file, a key, a value.

    The message is one line that names what is wrong and where (file, line,
    column or key). The CLI prints it without a traceback.
    """
