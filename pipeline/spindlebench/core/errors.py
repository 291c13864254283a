"""One exception type for every user-facing failure, so the CLI can print it as one line."""


class SpindlebenchError(Exception):
    """A problem with the user's input or environment, phrased as one line.

    The message names the file, line or key and says what is wrong; the CLI prints it as
    ``error: <message>`` and exits with status 2 instead of showing a traceback.
    """


#: Longest column name an error message quotes, and most close matches it names.
_QUOTED_CHARS, _CLOSE_MATCHES = 40, 3


def columns_hint(header: list[str] | tuple[str, ...], wanted: str) -> str:
    """What a "column not found" message says about the file's columns: their number and
    the few names close to ``wanted``, never the whole header (a file given by mistake, a
    password file say, would otherwise be echoed into the terminal and logs)."""
    import difflib

    close = difflib.get_close_matches(wanted, list(header), n=_CLOSE_MATCHES, cutoff=0.6)
    count = f"the file has {len(header)} column(s)"
    if not close:
        return f"{count}, none named like it"
    return f"{count}; closest: {', '.join(quoted_name(name) for name in close)}"


def quoted_name(name: str) -> str:
    """A column name as a message quotes it: in quotes, cut to a few words."""
    return repr(name if len(name) <= _QUOTED_CHARS else name[:_QUOTED_CHARS - 1] + "…")


class StaleCacheWarning(UserWarning):
    """A cache file does not match its inputs or its own checksum; it is recomputed (the
    per-user caches: soak states, translated models)."""
