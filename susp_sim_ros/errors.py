"""Named errors. Each message names the file, topic or parameter and what was expected.

The CLI maps :class:`SuspInputError` and its subclasses to exit code 2 (bad input) and prints only
the message, never a traceback.
"""


class SuspInputError(ValueError):
    """Bad input given to susp_sim_ros (file, topic, parameter or value)."""


class ConfigError(SuspInputError):
    """A config file (vehicle, variant, study, params) is missing, malformed or out of range."""


class RecordingError(SuspInputError):
    """An MCAP recording cannot be read as a test drive: not MCAP, truncated, corrupt, missing topics."""


class RecordingExistsError(SuspInputError):
    """Refusing to overwrite an existing recording."""


class CsvImportError(SuspInputError):
    """A CSV measurement file is malformed (names file, line and column)."""
