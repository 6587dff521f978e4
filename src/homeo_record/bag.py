"""Reading a recorded run back (``--record DIR``): a bag is hostile until decoded.

``load_run`` reads the run's settings from ``metadata.yaml`` (custom_data, ``record.RUN_INFO_KEY``),
rebuilds its scenario from the text stored there, and decodes every ``std_msgs/msg/String`` message
of a homeo topic with the contract's validation (``homeo_msgs_py.schemas.decode``). Anything that
is not a readable bag of this project is a ``BagError`` with a one-line reason; a single bad message
is skipped and counted.
"""

from __future__ import annotations

import json
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

from homeo_msgs_py.graph import key_of, schema_of

from .record import RUN_INFO_KEY
from .tap import STRING, string_data

MAX_METADATA = 16 << 20  # a metadata.yaml larger than this is not one of ours


class BagError(Exception):
    """Not a readable bag of a homeo run; ``str()`` is the reason (exit 2)."""


@dataclass
class RecordedRun:
    path: Path
    info: dict  # the run's settings (record.run_info)
    sc: object  # the scenario, rebuilt from the bag
    msgs: dict = field(default_factory=dict)  # topic key -> [Message] in bag order
    rejected: Counter = field(default_factory=Counter)  # topic key -> messages that did not decode
    diagnostics: int = 0

    def by_tick(self, key: str, final: bool = False) -> dict:
        """``tick -> fields`` of topic ``key`` (run 0; final messages only when ``final``)."""
        return {m.tick: m.fields for m in self.msgs.get(key, ())
                if m.run == 0 and bool(m.fields.get("final")) == final}

    def final_status(self) -> dict:
        """The last run status that carries metrics (the one the launcher printed them from)."""
        for m in reversed(self.msgs.get("run_status", [])):
            if m.fields.get("metrics"):
                return m.fields
        raise BagError(f"{self.path}: the bag has no run status with metrics (the run recorded no tick)")


def read_info(path: Path) -> dict:
    import yaml

    meta = path / "metadata.yaml"
    if not path.is_dir():
        raise BagError(f"{path}: not a bag folder" + ("" if path.exists() else " (it does not exist)"))
    if not meta.is_file():
        raise BagError(f"{path}: no metadata.yaml (not a rosbag2 bag)")
    try:
        if meta.stat().st_size > MAX_METADATA:
            raise BagError(f"{meta}: too large for a bag's metadata")
        doc = yaml.safe_load(meta.read_text())
        custom = doc["rosbag2_bagfile_information"].get("custom_data") or {}
        info = json.loads(custom[RUN_INFO_KEY])
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as exc:
        raise BagError(f"{meta}: unreadable ({type(exc).__name__})") from None
    except (KeyError, TypeError, AttributeError, ValueError, RecursionError):
        raise BagError(f"{meta}: not a homeo run's bag (no valid {RUN_INFO_KEY} in custom_data)") from None
    checks = {"graph": str, "iterations": int, "seed": int, "overrides": dict, "scenario": dict}
    for k, t in checks.items():
        if not isinstance(info, dict) or not isinstance(info.get(k), t) or isinstance(info.get(k), bool):
            raise BagError(f"{meta}: {RUN_INFO_KEY}.{k} is missing or not a {t.__name__}")
    if info["iterations"] < 0 or info["seed"] < 0:
        raise BagError(f"{meta}: {RUN_INFO_KEY} has a negative iterations or seed")
    return info


def load_run(path: str | Path) -> RecordedRun:
    from homeo_decision import codec
    from homeo_decision.scenario import ScenarioError, scenario_from_dict
    from homeo_msgs_py.schemas import Rejected, decode

    path = Path(path)
    info = read_info(path)
    try:
        sc = scenario_from_dict(info["scenario"], source=str(info.get("scenario_source", "<bag>")),
                                overrides=info["overrides"])
    except ScenarioError as exc:
        raise BagError(f"{path}: the scenario stored in the bag is invalid: {exc}") from None
    voc = codec.vocabulary(sc)
    run = RecordedRun(path, info, sc)
    try:
        from rosbags.rosbag2 import Reader

        with Reader(path) as reader:
            for conn, _t, raw in reader.messages():
                key = key_of(conn.topic)
                if key is None or key == "human_input":  # a person's inputs: kept in the bag, not replayed
                    run.diagnostics += conn.topic == "/diagnostics"
                    continue
                if conn.msgtype != STRING:
                    run.rejected[key] += 1
                    continue
                try:
                    run.msgs.setdefault(key, []).append(decode(string_data(bytes(raw)), voc, schema_of(key)))
                except (Rejected, ValueError):
                    run.rejected[key] += 1
    except BagError:
        raise
    except Exception as exc:  # noqa: BLE001 - whatever the reader trips over in a foreign file
        raise BagError(f"{path}: not a readable rosbag2 bag ({type(exc).__name__}: {str(exc)[:200]})") from None
    return run
