"""User-facing errors: each names the problem and the fix; the CLI prints them as one line."""


class KeyinError(Exception):
    """A problem with the user's input (config, data file, checkpoint) rather than a bug."""


class ConfigError(KeyinError):
    """A config value is out of range, unknown or inconsistent with another."""


class DatasetFormatError(KeyinError):
    """A dataset file is missing, corrupt, or does not match what the config expects."""


class CheckpointError(KeyinError):
    """A checkpoint is missing, unsafe to load, or belongs to another model or stage."""


class UnsafePathError(KeyinError):
    """A file name taken from a data or metrics file would leave the folder it must stay in."""
