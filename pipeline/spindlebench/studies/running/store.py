"""A study's results folder as a resumable store: one file per finished unit of work.

Each unit (a simulated recording, an evaluation) is written atomically when it finishes, so
the folder is always consistent: an interrupted study restarts, finds what is on disk, and
does only the rest. ``state.json`` pins the inputs: the study's *content* (its parsed,
canonicalised tables, so a comment, blank line or reordered key does not count as a change)
and the FMU's hash. Resuming with different inputs would mix incompatible results, so it is
refused with one line naming what differs.

A finished unit counts as done only while it is intact: every file the store writes has its
SHA-256 in ``manifest.json`` (a recording's CSV is checked against its sidecar's
``recording_sha256``), so a damaged, truncated or edited piece is named in a warning and
redone instead of read (random bytes in a stored CSV were a ``UnicodeDecodeError``).

Only one study process may work in a folder at a time: ``claim`` takes an exclusive lock
(``.lock``, an ``flock`` the system drops when the process ends, even by ``kill -9``); a
second process is refused with one line naming the process that holds it.
"""

from __future__ import annotations

import bisect
import contextlib
import errno
import fcntl
import hashlib
import io
import json
import os
import socket
import stat
import sys
import warnings
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

import pandas as pd

from spindlebench.core.atomic import atomic_path, write_bytes, write_text
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.paths import file_kind
from spindlebench.core.provenance import sha256_file, sha256_written
from spindlebench.formats.json_text import indented_json
from spindlebench.formats.recording import write_recording
from spindlebench.formats.table_csv import table_bytes, write_table

STATE_FILE = "state.json"
MANIFEST_FILE = "manifest.json"
LOCK_FILE = ".lock"
CONTENT_KEY = "study_content_sha256"
COMMAND_KEY = "command"
#: How a refusal names each pinned input.
_LABELS = {CONTENT_KEY: "study", "fmu_sha256": "FMU"}
_MAX_NAMED = 3


def canonical(content: Any) -> Any:
    """``content`` as it reads back from JSON, with 6000.0 written as 6000.

    Whole-number floats become ints so that ``6000`` and ``6000.0`` in a study file (the same
    value to the loader) pin the same content; dates become strings, tuples lists.
    """
    if isinstance(content, dict):
        return {str(key): canonical(value) for key, value in content.items()}
    if isinstance(content, list | tuple):
        return [canonical(value) for value in content]
    if isinstance(content, float) and content.is_integer():
        return int(content)
    if content is None or isinstance(content, bool | int | float | str):
        return content
    return str(content)


def content_sha256(content: Any) -> str:
    """Hex SHA-256 of the canonical JSON of ``content`` (sorted keys, no whitespace)."""
    text = json.dumps(canonical(content), sort_keys=True, ensure_ascii=False,
                      separators=(",", ":"))
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _flatten(table: Any, prefix: str = "") -> dict[str, Any]:
    if not isinstance(table, dict):
        return {prefix: table}
    out: dict[str, Any] = {}
    for key, value in table.items():
        out.update(_flatten(value, f"{prefix}.{key}" if prefix else str(key)))
    return out


_ABSENT: Any = object()


def _short(value: Any) -> str:
    text = "(absent)" if value is _ABSENT else json.dumps(value, ensure_ascii=False)
    return text if len(text) <= 40 else text[:39] + "…"


def differences(old: dict[str, Any], new: dict[str, Any]) -> list[str]:
    """``<section> key 'a.b': old → new`` for every leaf that differs between two contents.

    A content is a dict of sections (``"study file"``, ``"climate file"``), each a table.
    """
    out = []
    for section in sorted(set(old) | set(new)):
        before, after = _flatten(old.get(section, {})), _flatten(new.get(section, {}))
        for key in sorted(set(before) | set(after)):
            was, now = before.get(key, _ABSENT), after.get(key, _ABSENT)
            if was != now:
                out.append(f"{section} key '{key}': {_short(was)} → {_short(now)}")
    return out


def read_json_file(path: Path) -> Any:
    """The JSON value in ``path``; ``ValueError`` for anything that is not one readable JSON
    document (bad UTF-8, bad syntax, or nested so deep that the parser runs out of stack:
    a ``RecursionError`` was a traceback)."""
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
        raise ValueError(f"{type(exc).__name__}") from None


def _manifest_line(key: str, value: str) -> str:
    """One entry's line of ``manifest.json`` as ``json.dumps(..., indent=1)`` writes it."""
    return f" {json.dumps(key)}: {json.dumps(value)}"


class DamagedResultWarning(UserWarning):
    """A stored piece of a study no longer matches what was written; it is redone."""


class ResultStore:
    """Files under ``root``, addressed by relative paths, each checked to be intact."""

    def __init__(self, root: str | Path,
                 owned: Callable[[Path], bool] | None = None) -> None:
        """``owned``: whether an existing folder's entry belongs to this kind of output (a
        command that is not a study, ``compensate``); by default a folder is ours when it
        holds a study's ``state.json``."""
        self.root = Path(root)
        #: ``root`` as text, and the folders inside it ``path`` found to be real folders
        self._root_text = str(self.root).rstrip("/")
        self._real_folders: set[str] = set()
        #: each relative path asked for: its path, and the places on the way there as text
        self._paths: dict[str, tuple[Path, list[str]]] = {}
        self._owned = owned
        self._manifest: dict[str, str] | None = None
        #: the manifest's keys in sorted order and their lines of manifest.json, kept in step
        #: with it by ``_written`` and ``remove`` (None: not made yet)
        self._manifest_keys: list[str] | None = None
        self._manifest_lines: list[str] = []
        self._verified: dict[str, bool] = {}
        self._lock: int | None = None
        #: entries recorded since the manifest was last saved, and how many blocks defer
        #: its save (``one_manifest_save``)
        self._unsaved = False
        self._deferring = 0
        #: the folder's manifest was lost: a piece it does not name is redone without a
        #: warning per piece (the loss is said once)
        self._manifest_lost = False

    def path(self, relative: str | Path) -> Path:
        """``root / relative``, refused in one line if a link inside the folder is on the way:
        a linked ``runs/`` or piece would make the study write (or read) another folder's
        files. The root itself may be a link (results on another disk).

        A folder on the way found to be a real folder (not a link) is not looked at again
        in this process (the store's own folders do not turn into links while it holds
        their lock); the piece itself is looked at every time. Why: a sweep asks for ~22 000
        paths, and a pathlib walk with a link check per part was ~0.2 ms each."""
        text = os.fspath(relative)
        known = self._paths.get(text)
        if known is None:
            parts = [part for part in text.split("/") if part and part != "."]
            if text.startswith("/") or ".." in parts:
                raise ValueError(f"{relative}: not a path inside the results folder")
            on_the_way = [self._root_text + "/" + "/".join(parts[:number])
                          for number in range(1, len(parts) + 1)]
            known = Path(on_the_way[-1]) if parts else self.root, on_the_way
            self._paths[text] = known
        at, on_the_way = known
        for number, place in enumerate(on_the_way, start=1):
            if place in self._real_folders:
                continue
            try:
                mode = os.lstat(place).st_mode
            except (FileNotFoundError, NotADirectoryError):
                break  # nothing beyond is there either, so no link
            if stat.S_ISLNK(mode):
                raise SpindlebenchError(f"{Path(place)}: is a symbolic link inside the results "
                                        f"folder {self.root}; a study never writes through "
                                        "one (remove it, or use a new output folder)")
            if stat.S_ISDIR(mode) and number < len(on_the_way):
                self._real_folders.add(place)
        return at

    def exists(self, relative: str | Path) -> bool:
        """Whether the piece is there and intact; a damaged one is named and counts as
        missing (so the caller redoes it)."""
        return self.path(relative).is_file() and self.intact(relative)

    def has_recording(self, relative: str | Path) -> bool:
        """Whether the recording CSV ``relative`` is there, intact and has its JSON sidecar.

        The recording writer moves the CSV into place before its sidecar, so a study killed
        between the two moves leaves a CSV alone; without its sidecar (provenance, the
        ``recording_sha256`` it is checked against) it is not a finished recording: named in
        a warning and redone, not taken on trust."""
        if not self.exists(relative):
            return False
        key = Path(relative).as_posix()
        sidecar = self.path(key).with_suffix(".json")
        if sidecar.is_file():
            if self.intact(Path(key).with_suffix(".json")):
                if Path(key).with_suffix(".json").as_posix() not in self.manifest():
                    # vouched for by its CSV; unrecorded when the run stopped between the
                    # recording and the manifest write: recorded now, as a whole run would
                    self._written(Path(key).with_suffix(".json"))
                return True
            self._verified[key] = False
            return False
        warnings.warn(f"{self.path(key)}: incomplete (its sidecar {sidecar.name} is missing); "
                      "redoing it", DamagedResultWarning, stacklevel=2)
        self._verified[key] = False
        return False

    def intact(self, relative: str | Path) -> bool:
        """Whether the file still has the bytes the store (or the recording writer) wrote;
        a file written before the store kept hashes is taken on trust."""
        key = Path(relative).as_posix()
        if key not in self._verified:
            problem = self._damage(key)
            if problem is None and self._manifest_lost and key not in self.manifest() and \
                    not self._self_checked(key):
                self._verified[key] = False  # said once, in manifest()
                return False
            if problem:
                warnings.warn(f"{self.path(key)}: {problem}; redoing it",
                              DamagedResultWarning, stacklevel=3)
            self._verified[key] = problem is None
        return self._verified[key]

    def _damage(self, key: str) -> str | None:
        """What is wrong with the piece ``key`` (None: intact).

        Its SHA-256 must be the manifest's; a recording's CSV is checked against its
        sidecar's ``recording_sha256`` (so recordings, the expensive part, survive a lost
        manifest), and a sidecar the manifest does not know is vouched for by its CSV. Any
        other piece the manifest does not vouch for is not taken on trust: an evaluation
        edited after its manifest was deleted was resumed as if valid."""
        actual = sha256_file(self.path(key))
        expected = self.manifest().get(key)
        sidecar = self.path(key).with_suffix(".json")
        if expected is None and key.endswith(".csv") and sidecar.exists():  # a recording
            try:
                loaded = read_json_file(sidecar)
                expected = loaded.get("recording_sha256") if isinstance(loaded, dict) else None
            except (OSError, ValueError):
                return f"damaged (its sidecar {sidecar.name} is unreadable)"
            if not isinstance(expected, str):
                return f"damaged (its sidecar {sidecar.name} holds no recording_sha256)"
        if expected is None and key.endswith(".json") and self.path(key).with_suffix(
                ".csv").is_file():
            return None  # a recording's sidecar: its CSV is checked against it
        if expected is None and key.endswith(".csv") and key.startswith("runs/"):
            return None  # a recording without its sidecar: has_recording says so and redoes it
        if expected is None:
            return None if self._manifest_lost else (
                f"not in {MANIFEST_FILE} (written by a run that was killed before it could "
                "record it, or the manifest was edited)")
        if expected == actual:
            return None
        return (f"damaged (sha256 {actual[:12]}… is not the {expected[:12]}… it was "
                "written with)")

    def _self_checked(self, key: str) -> bool:
        """Whether the piece carries its own check: a recording (CSV with a sidecar) or a
        recording's sidecar."""
        path = self.path(key)
        twin = path.with_suffix(".json" if key.endswith(".csv") else ".csv")
        return key.endswith((".csv", ".json")) and twin.is_file() and key.startswith("runs/")

    def manifest(self) -> dict[str, str]:
        """Relative path → SHA-256 of every file this store wrote.

        A study folder (one with a ``state.json``) whose manifest is missing, unreadable or
        not a table of hashes has lost its record of what is intact: that is said once, and
        every piece that has no checksum of its own (all but the recordings) is redone."""
        if self._manifest is None:
            path = self.path(MANIFEST_FILE)
            problem = None
            try:
                loaded = read_json_file(path)
                if not isinstance(loaded, dict) or not all(
                        isinstance(v, str) for v in loaded.values()):
                    raise ValueError("not a table of hashes")
                self._manifest = {str(k): v for k, v in loaded.items()}
            except FileNotFoundError:
                problem = "is missing"
                self._manifest = {}
            except (OSError, ValueError) as exc:
                problem = f"is damaged ({exc})"
                self._manifest = {}
            if problem and self.path(STATE_FILE).is_file():
                self._manifest_lost = True
                warnings.warn(f"{path}: {problem}; the pieces it vouched for cannot be checked "
                              "and are redone (recordings are checked against their own "
                              "sidecars and kept)", DamagedResultWarning, stacklevel=3)
        return self._manifest

    def _written(self, relative: str | Path, save: bool = True,
                 data: bytes | None = None) -> None:
        """Record the piece's hash (of ``data``, its bytes as just written, when given: not
        read back from disk); the manifest is saved now unless ``save`` is False or a
        ``one_manifest_save`` block is open (then with the next save)."""
        key = Path(relative).as_posix()
        value = sha256_written(self.path(key), data)
        keys, lines = self._sorted_entries()
        at = bisect.bisect_left(keys, key)
        if at < len(keys) and keys[at] == key:
            lines[at] = _manifest_line(key, value)
        else:
            keys.insert(at, key)
            lines.insert(at, _manifest_line(key, value))
        self.manifest()[key] = value
        self._verified[key] = True
        self._changed(save)

    def _changed(self, save: bool = True) -> None:
        self._unsaved = True
        if save and not self._deferring:
            self._save_manifest()

    def _save_manifest(self) -> None:
        write_text(self.path(MANIFEST_FILE), self._manifest_text())
        self._unsaved = False

    @contextlib.contextmanager
    def one_manifest_save(self) -> Iterator[None]:
        """Record the pieces written (and removed) in the block with one save of the
        manifest at its end, for a unit of several files (an evaluation job's training runs).

        Why: each save rewrites the whole manifest, ~0.7 ms at a sweep's 2 000 entries, and
        a sweep made one per file. Killed inside the block, its pieces are not in the
        manifest: named and redone on resume, as a piece killed while being written is."""
        self._deferring += 1
        try:
            yield
        finally:
            self._deferring -= 1
            if not self._deferring and self._unsaved:
                self._save_manifest()

    def _sorted_entries(self) -> tuple[list[str], list[str]]:
        """The manifest's keys, sorted, and their lines (made once, then kept in step)."""
        if self._manifest_keys is None:
            manifest = self.manifest()
            self._manifest_keys = sorted(manifest)
            self._manifest_lines = [_manifest_line(key, manifest[key])
                                    for key in self._manifest_keys]
        return self._manifest_keys, self._manifest_lines

    def _manifest_text(self) -> str:
        """``json.dumps(dict(sorted(manifest.items())), indent=1) + "\\n"``, each entry's
        line made once and kept in sorted order (tested to be the same text).

        Why: the manifest is saved after every piece written, so a sweep of a thousand
        recordings and as many evaluations encoded its thousands of entries again each time
        (quadratic in the pieces), and then still sorted and checked every entry (1.3 CPU-s
        in a 1 008-experiment sweep); now a save joins the kept lines."""
        _, lines = self._sorted_entries()
        if not lines:
            return "{}\n"
        return "{\n" + ",\n".join(lines) + "\n}\n"

    def write_recording(self, relative: str | Path, frame: pd.DataFrame,
                        sidecar: dict[str, Any]) -> Path:
        """Write a recording (CSV, then its sidecar) and count it as intact from now on.

        The recording writer hashes the CSV into its own sidecar, not into the manifest, so
        the store must forget what it concluded about an earlier file at this path: a CSV
        found without its sidecar was marked not intact, and once redone it stayed so for the
        rest of the process (``place`` then found no runs and exited 2).

        A study writes hundreds of recordings in its one coordinating process: the
        sidecar's hash is saved with the manifest's next save (the next piece written, or
        ``unlock``): its CSV vouches for it meanwhile, and a resumed study records a sidecar
        the manifest lacks without a word (``has_recording``)."""
        target = self.path(relative)
        write_recording(target, frame, sidecar)
        self._verified[Path(relative).as_posix()] = True
        self._written(Path(relative).with_suffix(".json"), save=False)  # an edit is seen
        return target

    def remove(self, relative: str | Path) -> None:
        key = Path(relative).as_posix()
        self.path(key).unlink(missing_ok=True)
        self._verified.pop(key, None)
        if key in self.manifest():
            keys, lines = self._sorted_entries()  # made (if not yet) before the entry goes
            del self.manifest()[key]
            at = bisect.bisect_left(keys, key)
            del keys[at], lines[at]
            self._changed()

    def write_json(self, relative: str | Path, data: Any) -> Path:
        target = self.path(relative)
        # json.dumps(data, indent=2, ensure_ascii=False, default=str)'s text
        encoded = (indented_json(data, default=str) + "\n").encode("utf-8")
        write_bytes(target, encoded)
        self._written(relative, data=encoded)
        return target

    def read_json(self, relative: str | Path) -> Any:
        try:
            return read_json_file(self.path(relative))
        except ValueError as exc:
            raise SpindlebenchError(f"{self.path(relative)}: not readable JSON ({exc}); "
                                    "remove it and run again") from None

    def write_frame(self, relative: str | Path, frame: pd.DataFrame) -> Path:
        """Write a table (``table_csv.write_table``: pandas' bytes, faster)."""
        target = self.path(relative)
        data = table_bytes(frame)
        if data is None:  # pandas writes it
            with atomic_path(target) as tmp:
                data = write_table(tmp, frame)
        else:
            write_bytes(target, data)
        self._written(relative, data=data)
        return target

    def read_frames(self, relatives: Sequence[str | Path]) -> pd.DataFrame:
        """The rows of the tables ``relatives`` (at least one), in order, as
        ``pd.concat([pd.read_csv(path) for path in ...], ignore_index=True)`` gives them.

        Why: a sweep collects over a thousand small evaluation files, and pandas' reader
        cost ~1 ms a file, mostly its set-up; files that share one header (a sweep's, unless
        an evaluation failed) are parsed as one text, in half the CPU. That gives the same
        values and text (the same parser reads the same cells); a column's dtype can only
        differ where one file's cells are all empty and another's text (object there, str
        here), which writes the same CSV.

        The files are parsed as bytes (pandas decodes UTF-8 itself): decoding a large
        sweep's 66 MB to str and copying it into a ``StringIO`` cost more than a tenth of the
        parse. Line ends are translated as reading text does (a ``\\r`` in a quoted cell
        becomes ``\\n``), so the values are those the text read gave."""
        texts = [_text_lines(self.path(relative).read_bytes()) for relative in relatives]
        header, _, _ = texts[0].partition(b"\n")
        if len(texts) == 1 or any(not text.startswith(header + b"\n") for text in texts):
            return pd.concat([_parse(text, low_memory=True) for text in texts],
                             ignore_index=True)
        # one copy: each file after its header as a view (slicing the bytes, joining them
        # and adding the first file copied a large sweep's 66 MB three times, 0.2 CPU-s)
        skip = len(header) + 1
        return _parse(b"".join([texts[0], *(memoryview(text)[skip:] for text in texts[1:])]),
                      low_memory=False)

    def lock(self) -> None:
        """Take the folder's exclusive lock for the life of this process, or refuse in one
        line naming the process that holds it."""
        if self._lock is not None:
            return
        self._refuse_foreign_folder()  # no lock file in a folder that is not ours
        self.root.mkdir(parents=True, exist_ok=True)
        path = self.root / LOCK_FILE
        try:  # never through a link (its target would be truncated), nor a FIFO or device
            handle = os.open(path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_NONBLOCK
                             | os.O_CLOEXEC, 0o666)
        except OSError as exc:
            if exc.errno != errno.ELOOP:
                raise
            raise SpindlebenchError(f"{path}: the lock file is a symbolic link; a study never "
                                    "writes through one (remove it)") from None
        if not stat.S_ISREG(os.fstat(handle).st_mode):
            os.close(handle)
            raise SpindlebenchError(f"{path}: the lock file is not a regular file (remove it)")
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.read(handle, 400).decode("utf-8", "replace").strip() or "another process"
            os.close(handle)
            raise SpindlebenchError(f"{self.root}: in use by {holder}; wait for it to finish "
                                    "or use another output folder") from None
        os.ftruncate(handle, 0)
        command = " ".join(["spindlebench", *sys.argv[1:3]]) if sys.argv else "python"
        os.write(handle, f"process {os.getpid()} on {socket.gethostname()} "
                         f"({command})\n".encode())
        self._lock = handle  # kept open: the lock lasts as long as this process

    def unlock(self) -> None:
        """Save what the manifest has not saved yet, and release the folder."""
        if self._unsaved:
            self._save_manifest()
        if self._lock is not None:
            os.close(self._lock)
            self._lock = None

    @contextlib.contextmanager
    def locked(self) -> Iterator[ResultStore]:
        """Hold the folder's lock for the block (re-entrant: an outer holder keeps it)."""
        if self._lock is not None:
            yield self
            return
        self.lock()
        try:
            yield self
        finally:
            self.unlock()

    def _refuse_foreign_folder(self) -> None:
        if self.root.exists() and not self.root.is_dir():
            raise SpindlebenchError(f"{self.root}: exists and is not a folder (it is "
                                    f"{file_kind(self.root)}); choose a new or empty folder")
        if self._owned is not None:
            foreign = sorted(p.name for p in self.root.iterdir() if p.name != LOCK_FILE
                             and not p.name.endswith(".part") and not self._owned(p)) \
                if self.root.exists() else []
            if foreign:
                raise SpindlebenchError(f"{self.root}: holds files this command does not write "
                                        f"({', '.join(foreign[:3])}); choose an empty or new "
                                        "folder")
            return
        if not self.path(STATE_FILE).is_file() and self.root.exists() and any(
                p.name != LOCK_FILE for p in self.root.iterdir()):
            raise SpindlebenchError(f"{self.root}: exists and is not a study results folder; "
                                    "choose an empty or new folder")
        self._state()  # a damaged state.json: refused before the lock file is made

    def claim(self, content: dict[str, Any], hashes: dict[str, str],
              command: str | None = None) -> bool:
        """Start or resume: pin the inputs or check them against the pinned ones.

        ``content``: the study's canonical content (sections of tables, see
        :func:`differences`); its hash is pinned and the content itself is kept, so a refusal
        names the keys that changed. ``hashes``: other inputs pinned by hash (the FMU).
        ``command``: the command whose folder this is (``sweep``, ``place``): another
        command's results in it would be mixed with its own (a folder made before commands
        were pinned is checked on its content only).
        Returns True when resuming existing work; refuses a folder made from other inputs.
        """
        content = canonical(content)
        inputs = {**({COMMAND_KEY: command} if command else {}),
                  CONTENT_KEY: content_sha256(content), **hashes}
        self.lock()  # held until unlock(), the end of ``locked()`` or of the process
        state = self._state()
        self.manifest()  # before state.json is written: a new folder has lost nothing
        if state is not None:
            recorded = state["inputs"]
            for key, value in inputs.items():
                if key == COMMAND_KEY and key not in recorded:
                    continue
                if recorded.get(key) != value:
                    raise self._refusal(key, recorded.get(key), value, state.get("content"),
                                        content)
            return True
        self.write_json(STATE_FILE, {"inputs": inputs, "content": content})
        return False

    def _state(self) -> dict[str, Any] | None:
        """The folder's ``state.json`` (None if there is none), refused in one line unless it
        is a study state: an object whose ``inputs`` pin a content hash, and whose content,
        when kept, still has that hash (an edited state would name the wrong differences)."""
        state_path = self.path(STATE_FILE)
        if not state_path.is_file():
            return None
        try:
            state = read_json_file(state_path)
            recorded = state["inputs"]
            if not isinstance(recorded, dict) or not isinstance(recorded.get(CONTENT_KEY), str):
                raise TypeError
        except (OSError, ValueError, KeyError, TypeError, IndexError):
            raise SpindlebenchError(f"{state_path}: not a study state file; "
                                    "choose another output folder") from None
        kept = state.get("content")
        if kept is not None and content_sha256(kept) != recorded[CONTENT_KEY]:
            raise SpindlebenchError(f"{state_path}: edited (its study content no longer has "
                                    "the hash it pins); choose another output folder")
        return state

    def _refusal(self, key: str, was: Any, now: str, old_content: Any,
                 new_content: dict[str, Any]) -> SpindlebenchError:
        if key == COMMAND_KEY:
            return SpindlebenchError(f"{self.root}: holds the results of 'spindlebench {was}', "
                                     f"not of '{now}'; use a new output folder")
        label = _LABELS.get(key, key)
        named = differences(old_content, new_content) if (
            key == CONTENT_KEY and isinstance(old_content, dict)) else []
        if named:
            more = len(named) - _MAX_NAMED
            what = "; ".join(named[:_MAX_NAMED]) + (f"; and {more} more" if more > 0 else "")
        else:
            what = f"sha256 {str(was)[:12]}… vs {now[:12]}…"
        return SpindlebenchError(f"{self.root}: holds results of a different {label} ({what}); "
                                 "use a new output folder to run this study")


def _text_lines(data: bytes) -> bytes:
    """``data`` with its line ends as ``read_text`` gives them (``\\r\\n`` and ``\\r``
    become ``\\n``); a result file written here has none but in a quoted cell."""
    return data.replace(b"\r\n", b"\n").replace(b"\r", b"\n") if b"\r" in data else data


def _parse(data: bytes, low_memory: bool) -> pd.DataFrame:
    """The table in ``data``, as ``pd.read_csv`` of its UTF-8 text reads it."""
    return pd.read_csv(io.BytesIO(data), encoding="utf-8", keep_default_na=True,
                       low_memory=low_memory)
