"""The config's intention cues: a keyword or gesture names the intention (no qi import).

Until the Bayesian recogniser (``homeo_intention``) takes over, the field driver and the graph's
oracle mode read the intention the user showed from ``intention_cues`` of the config; the
symbols are those of the scenario's observation alphabets.
"""

from __future__ import annotations


class IntentionCues:
    """Keyword / gesture -> intention, from the config's ``intention_cues`` (the keyword first)."""

    def __init__(self, cues: dict, intentions):
        self.kw = dict(cues.get("keywords", {}))
        self.gest = dict(cues.get("gestures", {}))
        known = set(intentions)
        for name in list(self.kw.values()) + list(self.gest.values()):
            if name not in known:
                raise ValueError(f"intention cue names unknown intention {name!r}")

    def __call__(self, obs: dict) -> str | None:
        if obs.get("keyword") in self.kw:
            return self.kw[obs["keyword"]]
        if obs.get("gesture") in self.gest:
            return self.gest[obs["gesture"]]
        return None
