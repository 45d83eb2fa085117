"""The design-space emulator: the default predictor, faithful to the FE over the box.

    from surrogate.emulator import fit_emulator, load_emulator, save_emulator
    e = load_emulator("service/data/emulator.json")
    e.predict(design, [500, 1000, 1500])     # Prediction (angle, band, force, volume)
    e.inverse(design, [30, 60])              # InversePrediction (pressure, band)

Method and accuracy: docs/surrogate.md.
"""

from surrogate.emulator.build import fit_emulator
from surrogate.emulator.emulator import Emulator
from surrogate.emulator.file import load_emulator, save_emulator

__all__ = ["Emulator", "fit_emulator", "load_emulator", "save_emulator"]
