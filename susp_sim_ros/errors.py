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


class TopicMapError(ConfigError):
    """A topic map (``--topic-map``) or channel map (``--channel-map``) is malformed: names the file, the key
    and what was expected."""


class NotRos2RecordingError(RecordingError):
    """A recording that is not a ROS 2 recording (another MCAP profile, non-CDR messages, a ROS 1 bag)."""


class UnknownMessageTypeError(RecordingError):
    """A topic the command needs carries a message type that cannot be decoded (no schema, unknown type)."""


class MeasurementImportError(SuspInputError):
    """A measurement file (MDF4) or road file (OpenCRG) cannot be imported (names file, channel, cause)."""
