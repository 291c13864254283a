"""A study's results folder as a resumable store: one file per finished unit of work.

Each unit (a simulated recording, an evaluation) is written atomically when it finishes, so
the folder is always consistent: an interrupted study restarts, finds what is on disk, and
does only the rest. ``state.json`` pins the inputs (study file hash, FMU hash); resuming with
different inputs would mix incompatible results, so it is refused with a clear message.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pandas as pd

from spindlebench.atomic import atomic_path, write_text
from spindlebench.errors import SpindlebenchError

STATE_FILE = "state.json"


class ResultStore:
    """Files under ``root``, addressed by relative paths."""

    def __init__(self, root: str | Path) -> None:
        self.root = Path(root)

    def path(self, relative: str | Path) -> Path:
        return self.root / relative

    def exists(self, relative: str | Path) -> bool:
        return self.path(relative).is_file()

    def remove(self, relative: str | Path) -> None:
        self.path(relative).unlink(missing_ok=True)

    def write_json(self, relative: str | Path, data: Any) -> Path:
        target = self.path(relative)
        write_text(target, json.dumps(data, indent=2, ensure_ascii=False, default=str) + "\n")
        return target

    def read_json(self, relative: str | Path) -> Any:
        return json.loads(self.path(relative).read_text(encoding="utf-8"))

    def write_frame(self, relative: str | Path, frame: pd.DataFrame) -> Path:
        target = self.path(relative)
        with atomic_path(target) as tmp:
            frame.to_csv(tmp, index=False, lineterminator="\n")
        return target

    def read_frame(self, relative: str | Path) -> pd.DataFrame:
        return pd.read_csv(self.path(relative), keep_default_na=True)

    def claim(self, inputs: dict[str, str]) -> bool:
        """Start or resume: record ``inputs`` or check them against the recorded ones.

        Returns True when resuming existing work; refuses a folder made from other inputs.
        """
        state_path = self.path(STATE_FILE)
        if state_path.is_file():
            try:
                recorded = json.loads(state_path.read_text(encoding="utf-8"))["inputs"]
            except (json.JSONDecodeError, KeyError, TypeError):
                raise SpindlebenchError(f"{state_path}: not a study state file; "
                                        "choose another output folder") from None
            for key, value in inputs.items():
                if recorded.get(key) != value:
                    raise SpindlebenchError(
                        f"{self.root}: holds results of a different {key} "
                        f"({str(recorded.get(key))[:12]}… vs {value[:12]}…); "
                        "use a new output folder to run this study")
            return True
        if self.root.exists() and any(self.root.iterdir()) and not state_path.is_file():
            raise SpindlebenchError(f"{self.root}: exists and is not a study results folder; "
                                    "choose an empty or new folder")
        self.write_json(STATE_FILE, {"inputs": inputs})
        return False
