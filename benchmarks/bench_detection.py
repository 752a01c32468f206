"""The receiver's detection threshold: false-alarm and miss rates on simulated windows.

Run: python benchmarks/bench_detection.py [--windows 20000] [--seed 0]

Three measurements, one JSON line each:

1. **false alarms**: windows of noise alone at several thresholds P_fa; the share the
   receiver reports as heard, against the bound P_fa it promises (simulation.receiver,
   "Detection": η = Q⁻¹(P_fa / 2Nc));
2. **miss rate against the correlation SNR**: one direct path whose correlation peak
   stands d noise standard deviations high, d = η + margin; the share missed against
   Φ(η − d) (the pick on the true lag) and Φ(η − d − 1);
3. **the room's SNR model**: in a 30 × 16 × 6 m hall (ISO 9613-1 air, the 90 ms chirp of
   examples/hall.toml, P_fa = 10⁻³), one anchor and nodes at increasing distance with the
   SNR rule's noise: the share of realizations heard (simulated) and whether the bound's
   coverage model (analysis.heard) says heard, per distance. Air absorption and
   spreading make the far anchor fade.
"""

import argparse
import dataclasses

import numpy as np
from _common import emit
from scipy.special import ndtr

import analysis
from simulation import Chirp, Receiver, Room, System
from simulation.evaluation import RangingScene
from simulation.receiver import HEARD, NOT_HEARD, dsp_for
from simulation.synthesis import synthesize


def false_alarms(n: int, rng) -> list[dict]:
    out = []
    for fa in (1e-1, 1e-2, 1e-3):
        rx = Receiver(false_alarm=fa)
        dsp = dsp_for(Chirp(), rx)
        windows = rng.standard_normal((n, rx.window))
        _, status = dsp.detect(windows, 343.0, 1.0, System(receiver=rx).delays, 0.01)
        rate = float(np.mean(status == HEARD))
        out.append({"case": "noise only", "false_alarm_bound": fa, "eta": dsp.threshold,
                    "windows": n, "heard_share": rate, "within_bound": rate <= fa})  # fmt: skip
    return out


def misses(n: int, rng) -> list[dict]:
    rx = Receiver(false_alarm=1e-3)
    sig = System(receiver=rx)
    dsp = dsp_for(sig.chirp, rx)
    tau = 0.010
    clean = synthesize(np.array([[tau]]), np.ones((1, 1)), sig.chirp, rx)[0]
    k0, peak = dsp.picks(clean[None])
    out = []
    for margin in (-2.0, -1.0, 0.0, 1.0, 2.0, 3.0):
        d = dsp.threshold + margin
        sigma = peak[0] / (d * dsp.noise_gain[k0[0]])
        windows = clean[None, :] + sigma * rng.standard_normal((n, clean.size))
        _, status = dsp.detect(windows, 343.0, sigma, sig.delays, tau)
        out.append({
            "case": "one path", "eta": dsp.threshold, "snr_sigmas": d, "windows": n,
            "miss_share": float(np.mean(status == NOT_HEARD)),
            "bound_upper": float(ndtr(dsp.threshold - d)),
            "bound_lower": float(ndtr(dsp.threshold - d - 1.0)),
        })  # fmt: skip
    return out


def hall_fade(realizations: int, rng) -> list[dict]:
    hall = Room.from_toml("examples/hall.toml")
    hall = dataclasses.replace(hall, size=(30.0, 16.0, 6.0), zones=(), zone_names=())
    anchor = np.array([[0.03, 8.0, 5.0]])
    d = np.array([2.0, 5.0, 8.0, 10.0, 12.0, 14.0, 16.0, 18.0, 20.0, 24.0, 28.0])
    nodes = np.stack([0.03 + d, np.full_like(d, 8.0), np.full_like(d, 1.2)], axis=1)
    system = System.from_toml("examples/hall.toml")
    scene = RangingScene(hall, anchor, nodes, system=system)
    windows = np.stack([scene.noisy_windows(rng) for _ in range(realizations)])
    _, status = scene.detect(windows)
    bound = analysis.heard(hall, anchor, nodes, system=system)[:, 0]
    dist = np.linalg.norm(nodes - anchor, axis=1)
    return [
        {
            "case": "hall, ISO air",
            "distance_m": float(dist[i]),
            "realizations": realizations,
            "heard_share": float(np.mean(status[:, i, 0] == HEARD)),
            "bound_says_heard": bool(bound[i]),
            "reach_m": system.reach(hall.speed_of_sound),
        }  # fmt: skip
        for i in range(len(d))
    ]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--windows", type=int, default=20000, help="windows per measurement")
    ap.add_argument("--realizations", type=int, default=400, help="realizations in the hall")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    for row in false_alarms(args.windows, rng) + misses(args.windows // 4, rng):
        emit("detection", **row)
    for row in hall_fade(args.realizations, rng):
        emit("detection", **row)


if __name__ == "__main__":
    main()
