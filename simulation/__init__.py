"""The lowest layer: room, chirp, propagation, receiver DSP, positioning, Monte Carlo.

Imports neither :mod:`analysis` nor :mod:`placement`.
"""

from simulation.chirp import Chirp
from simulation.directivity import aim_vectors, cardioid
from simulation.evaluation import Evaluation, RangingScene, evaluate_layout, simulate_ranges
from simulation.multipath import ImageSet, Paths, compute_paths
from simulation.noise import noise_sigma, reference_nodes
from simulation.positioning import PositionFix, locate
from simulation.received import received_windows
from simulation.receiver import Dsp, Receiver, dsp_for, reference_chain
from simulation.room import SURFACES, Room
from simulation.system import PRESETS, Positioning, System

__all__ = [
    "SURFACES",
    "Chirp",
    "Dsp",
    "Evaluation",
    "ImageSet",
    "Paths",
    "PositionFix",
    "RangingScene",
    "Receiver",
    "Room",
    "PRESETS",
    "Positioning",
    "System",
    "aim_vectors",
    "cardioid",
    "compute_paths",
    "dsp_for",
    "evaluate_layout",
    "locate",
    "noise_sigma",
    "received_windows",
    "reference_chain",
    "reference_nodes",
    "simulate_ranges",
]
