"""The lowest layer: room, chirp, propagation, receiver DSP, positioning, Monte Carlo.

Imports neither :mod:`analysis` nor :mod:`placement`.
"""

from simulation.chirp import Chirp
from simulation.directivity import aim_vectors, cardioid
from simulation.receiver import Receiver
from simulation.room import SURFACES, Room

__all__ = ["SURFACES", "Chirp", "Receiver", "Room", "aim_vectors", "cardioid"]
