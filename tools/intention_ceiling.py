"""Accuracy ceiling of intention recognition (docs/FIDELITY.md, "Intention recognition").

    .venv/bin/python tools/intention_ceiling.py [--none 0.5]

The expected accuracy (threshold 0) of a network with the simulated user's true habits (the
Bayes-optimal ceiling) and of the textbook prior, against the per-channel noise level, when a tick
wants nothing with probability --none and each intention is otherwise equally likely.
"""

from __future__ import annotations

import argparse

import numpy as np

from homeo_decision.scenario import OBS_CHANNELS, load_scenario
from homeo_intention.em import Params
from homeo_intention.model import prior_params


def habits(sc, freq, noise: float) -> Params:
    likes = []
    for ch in OBS_CHANNELS:
        H = np.array(sc.observations.habits[ch])
        likes.append((1 - noise) * H + noise / H.shape[1])  # what SimHuman.observe draws
    return Params(np.array(freq), likes)


def accuracy(model: Params, truth: Params) -> float:
    K = len(truth.pi)
    Jt = np.einsum("k,kg,km,kw->kgmw", truth.pi, *truth.likes).reshape(K, -1)
    Jm = np.einsum("k,kg,km,kw->kgmw", model.pi, *model.likes).reshape(K, -1)
    decision = Jm.argmax(axis=0)  # Eq 2.10
    return float(Jt[decision, np.arange(Jt.shape[1])].sum())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--none", type=float, default=0.5, help="share of ticks without an intention")
    args = ap.parse_args()
    sc = load_scenario()
    K = len(sc.intention_names)
    freq = [args.none] + [(1 - args.none) / (K - 1)] * (K - 1)
    print("noise  ceiling  textbook")
    for noise in (0.0, 0.01, 0.02, 0.05, 0.1, 0.2):
        truth = habits(sc, freq, noise)
        print(f"{noise:5.2f}  {accuracy(truth, truth):7.3f}  {accuracy(prior_params(sc), truth):8.3f}")


if __name__ == "__main__":
    main()
