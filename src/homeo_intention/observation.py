"""Observations of the human: one symbol per channel (gesture, movement, keyword), as a cell index.

The recogniser keeps every table over *cells*: the product of the channels' alphabets, each
extended by one "unobserved" state (the last index), so a missing or ``None`` channel is
summed out of the posterior instead of being an error. An unknown symbol is an error.
"""

from __future__ import annotations

from homeo_decision.scenario import OBS_CHANNELS, Scenario, ScenarioError


class UnknownObservation(ValueError):
    """An observation the scenario's alphabets do not contain; the message names it."""


class ObservationCoder:
    """Maps an observation dict to its cell index (and back) for one scenario's alphabets."""

    def __init__(self, sc: Scenario):
        if sc.observations is None:
            raise ScenarioError(f"{sc.source}: the scenario has no 'observations' block (alphabets and the network's "
                                "prior), so it cannot run intention recognition")
        self.alphabets = [tuple(sc.observations.alphabets[ch]) for ch in OBS_CHANNELS]
        self.sizes = [len(a) for a in self.alphabets]  # observed states per channel
        self.shape = tuple(n + 1 for n in self.sizes)  # + "unobserved"
        self.n_cells = self.shape[0] * self.shape[1] * self.shape[2]
        self._index = [{s: i for i, s in enumerate(a)} for a in self.alphabets]

    def cell(self, obs: dict) -> int:
        """Cell of ``obs`` (keys ``gesture``, ``movement``, ``keyword``; missing/None = unobserved)."""
        if not isinstance(obs, dict):
            raise UnknownObservation(f"an observation must be a dict of {', '.join(OBS_CHANNELS)}, not {type(obs).__name__}")
        c = 0
        for ch, idx, n1 in zip(OBS_CHANNELS, self._index, self.shape):
            sym = obs.get(ch)
            if sym is None:
                i = n1 - 1
            else:
                i = idx.get(sym, -1)
                if i < 0:
                    raise UnknownObservation(f"unknown {ch} {sym!r}; known: {', '.join(idx)}")
            c = c * n1 + i
        return c

    def symbols(self, cell: int) -> dict:
        """The observation of a cell (unobserved channels are None)."""
        out = {}
        for ch, alpha, n1 in reversed(list(zip(OBS_CHANNELS, self.alphabets, self.shape))):
            cell, i = divmod(cell, n1)
            out[ch] = alpha[i] if i < len(alpha) else None
        return {ch: out[ch] for ch in OBS_CHANNELS}
