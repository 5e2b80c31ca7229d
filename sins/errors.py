"""The one exception type for bad input that crosses the project's edge."""


class SinsInputError(ValueError):
    """Bad input from a user: a file, a key, a value.

    The message is one line that names what is wrong and where (file, line,
    column or key). The CLI prints it without a traceback.
    """


class MissingInputError(SinsInputError):
    """Bad input that another input would mend. ``needs`` names that input in the library's terms
    (``"truth"``); the CLI says which flag gives it, so library messages never name flags."""

    def __init__(self, message: str, needs: str) -> None:
        super().__init__(message)
        self.needs = needs


class ArgumentError(SinsInputError):
    """Bad input that names the library's own arguments (``names``, in ``template``'s ``{names}``): a
    reader's option that does not apply, say. The command line says them as its flags
    (:meth:`said`); the library's message names the arguments a caller passed."""

    def __init__(self, template: str, names: tuple[str, ...]) -> None:
        self.template, self.names = template, names
        super().__init__(template.format(names=", ".join(names)))

    def said(self, flags: dict[str, str]) -> str:
        """The message with each argument named by its entry in ``flags`` (a CLI's ``--topic``)."""
        return self.template.format(names=", ".join(flags.get(n, n) for n in self.names))


class LateStartError(SinsInputError):
    """Increments whose first row does not end after the start they were given (``first_end_s``, s):
    the reader that took the start from a reference names that reference instead."""

    def __init__(self, message: str, first_end_s: float) -> None:
        super().__init__(message)
        self.first_end_s = first_end_s


def naming(where: str, exc: Exception) -> SinsInputError:
    """``exc``'s message as a :class:`SinsInputError` that names ``where``: prefixed with it, unless it
    opens with it already (a strategy's own message may name the data)."""
    text = str(exc)
    return SinsInputError(text if text.startswith(where) else f"{where}: {text}")


__all__ = [
    "ArgumentError",
    "LateStartError",
    "MissingInputError",
    "SinsInputError",
    "naming",
]
