"""Regenerate requirements.lock from the current venv.

ROS wheels install extra ``*.egg-info`` records (e.g. ``action_msgs``) next to their
real distributions; those are not installable names, so only ``.dist-info`` ones are kept.
Usage: .venv/bin/python tools/lock.py > requirements.lock
"""

from importlib.metadata import distributions

SKIP = {"homeo-robot", "pip"}

lines = set()
for d in distributions():
    path = str(getattr(d, "_path", ""))
    name = d.metadata["Name"]
    if not path.endswith(".dist-info") or name.lower() in SKIP:
        continue
    lines.add(f"{name}=={d.version}")
print("\n".join(sorted(lines, key=str.lower)))
