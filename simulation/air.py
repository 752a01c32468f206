"""Air absorption of ultrasound (docs/model.md, "Air absorption").

Two models, selected by ``Room.air_absorption``:

- a number a (1/m): the paper's single coefficient, the same at every frequency; a path of
  length d keeps the amplitude factor exp(−a·d/2) (a is an energy coefficient: the paper's
  0.0875 1/m is 0.38 dB/m);
- ``"iso9613"``: the pure-tone attenuation coefficient of ISO 9613-1:1993 (eq. 5), from the
  air's temperature, relative humidity and pressure, per frequency. At 20 °C and 50 % it is
  0.73 / 1.13 / 1.49 dB/m at 25 / 35 / 45 kHz: over 20 m that is 23 dB in the chirp's band
  against the paper's 8 dB.

:func:`iso9613_db_per_m` is the standard's formula; :func:`energy_coefficient` turns dB/m
into the energy coefficient (1/m) that the propagation uses, so that both models enter as
exp(−m(f)·d/2).
"""

from __future__ import annotations

import math

import numpy as np

#: the frequency-dependent model's name in ``Room.air_absorption``
ISO9613 = "iso9613"
#: decibels per neper of energy: 10·log10(e); an energy coefficient m (1/m) is
#: m·DB_PER_NEPER dB/m
DB_PER_NEPER = 10.0 / math.log(10.0)
#: ISO 9613-1 reference values: pressure (kPa), temperature (K), triple-point isotherm (K)
REFERENCE_PRESSURE = 101.325
REFERENCE_TEMPERATURE = 293.15
TRIPLE_POINT = 273.16
#: accepted relative humidity (%) and pressure (kPa)
HUMIDITY_RANGE = (0.0, 100.0)
PRESSURE_RANGE = (50.0, 110.0)


def molar_water_vapour(temperature: float, humidity: float, pressure: float) -> float:
    """Molar concentration h (%) of water vapour (ISO 9613-1, Annex B, eq. B.1–B.3) from
    the temperature (°C), relative humidity (%) and pressure (kPa)."""
    T = temperature + 273.15
    C = -6.8346 * (TRIPLE_POINT / T) ** 1.261 + 4.6151
    return humidity * 10.0**C * REFERENCE_PRESSURE / pressure


def iso9613_db_per_m(
    frequency, temperature: float = 20.0, humidity: float = 50.0, pressure: float = 101.325
) -> np.ndarray:
    """Pure-tone attenuation coefficient α(f) in dB/m of ISO 9613-1:1993, eq. (5).

    frequency in Hz (any shape), temperature in °C, relative humidity in %, pressure in kPa.
    The oxygen and nitrogen relaxation frequencies are eq. (3) and (4):

        α = 8.686 f² [1.84e-11 (pa/pr)⁻¹ (T/T0)^½
                      + (T/T0)^(−5/2) (0.01275 e^(−2239.1/T) / (frO + f²/frO)
                                       + 0.1068 e^(−3352/T) / (frN + f²/frN))].
    """
    f = np.asarray(frequency, dtype=float)
    T = temperature + 273.15
    tr = T / REFERENCE_TEMPERATURE
    pr = pressure / REFERENCE_PRESSURE
    h = molar_water_vapour(temperature, humidity, pressure)
    fr_o = pr * (24.0 + 4.04e4 * h * (0.02 + h) / (0.391 + h))
    fr_n = pr * tr**-0.5 * (9.0 + 280.0 * h * math.exp(-4.170 * (tr ** (-1.0 / 3.0) - 1.0)))
    classical = 1.84e-11 / pr * tr**0.5
    o2 = 0.01275 * math.exp(-2239.1 / T) / (fr_o + f * f / fr_o)
    n2 = 0.1068 * math.exp(-3352.0 / T) / (fr_n + f * f / fr_n)
    return 8.686 * f * f * (classical + tr**-2.5 * (o2 + n2))


def energy_coefficient(db_per_m) -> np.ndarray:
    """The energy attenuation coefficient m (1/m) of an attenuation in dB/m: the amplitude
    of a path of length d is scaled by exp(−m·d/2) = 10^(−α·d/20)."""
    return np.asarray(db_per_m, dtype=float) / DB_PER_NEPER
