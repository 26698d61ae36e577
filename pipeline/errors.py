"""User-facing errors: one line, naming the file and the key or line, exit code 2."""

from __future__ import annotations


class UserError(Exception):
    """A problem with what the user gave us (scene, input file, command line).

    Parameters
    ----------
    message
        What is wrong, in words a user can act on.
    file
        The file at fault, if any.
    key
        The dotted scene key (``substrate.H``) or ``line N`` at fault, if any.
    """

    exit_code = 2

    def __init__(self, message: str, *, file: str | None = None, key: str | None = None):
        self.message = message
        self.file = str(file) if file is not None else None
        self.key = key
        super().__init__(self.format())

    def format(self) -> str:
        where = ":".join(part for part in (self.file, self.key) if part)
        return f"{where}: {self.message}" if where else self.message

    def located(self, *, file: str | None = None, key: str | None = None) -> "UserError":
        """Return a copy that names ``file``/``key`` where this error did not yet."""
        return UserError(
            self.message,
            file=self.file or (str(file) if file is not None else None),
            key=self.key or key,
        )


class ComputationError(Exception):
    """A numerical method failed (no convergence, ...). Exit code 1; the message says where."""

    exit_code = 1


class OutputError(UserError):
    """A result could not be written (full disk, read-only folder, a folder where a file should
    be, ...). One line naming the file; the CLI exits 1 (the scene is fine, the machine is not).
    Raised only after the temporary file is removed: nothing of that result is kept."""

    exit_code = 1

    def located(self, *, file: str | None = None, key: str | None = None) -> "OutputError":
        return OutputError(self.message, file=self.file or file, key=self.key or key)
