"""One exception type for every user-facing failure, so the CLI can print it as one line."""


class SpindlebenchError(Exception):
    """A problem with the user's input or environment, phrased as one line.

    The message names the file, line or key and says what is wrong; the CLI prints it as
    ``error: <message>`` and exits with status 2 instead of showing a traceback.
    """
