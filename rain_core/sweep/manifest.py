"""The dataset root's manifest: ``manifest.jsonl``, one JSON line per sequence (id, params, seed, frames, status,
checksum, error, seconds), in the sweep's order. It is rewritten whole through a temporary file and a rename
after every finished sequence, so an interrupted sweep always leaves a consistent manifest. ``load_manifest``
reads it back (what a loader of the dataset reads)."""

from __future__ import annotations

import json
import os
from pathlib import Path

NAME = "manifest.jsonl"


def load_manifest(root) -> dict[str, dict]:
    """id → line of the manifest under ``root`` (empty if there is none yet)."""
    path = Path(root) / NAME
    if not path.is_file():
        return {}
    lines = {}
    for number, text in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        if not text.strip():
            continue
        try:
            entry = json.loads(text)
        except json.JSONDecodeError:
            raise ValueError(f"{path}:{number}: not a JSON line (a damaged manifest: delete it to start over)") \
                from None
        lines[entry["id"]] = entry
    return lines


def write_manifest(root, lines: list[dict]) -> Path:
    """Replace the manifest under ``root`` with ``lines`` (atomically)."""
    path = Path(root) / NAME
    tmp = path.with_suffix(".jsonl.tmp")
    with open(tmp, "w", encoding="utf-8") as handle:
        for entry in lines:
            handle.write(json.dumps(entry, sort_keys=True) + "\n")
        handle.flush()
        os.fsync(handle.fileno())
    os.replace(tmp, path)
    return path
