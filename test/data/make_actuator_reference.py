# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Write actuator_reference.npz: MagnetostrictiveActuator outputs of the code before issue 19.

Run once at commit b9ad4fe (the actuator with its effects hard-coded in the compiled
kernel) with ``python test/data/make_actuator_reference.py``; test/test_actuator_reference.py
checks that the actuator built from the effect registry returns the same arrays.  The
inputs (time, current) and each case's config are stored beside the outputs, so the test
depends on nothing else of the old code.
"""

import json
from pathlib import Path

from mpi_ros.plant.actuator import ActuatorConfig, MagnetostrictiveActuator
from mpi_ros.plant.excitation import identification_excitation
import numpy as np

#: Case name -> ActuatorConfig keywords (every effect alone, all together, sensor zero).
CASES = {
    'plain': {},
    'creep': {'creep_gain': 0.08, 'creep_lag_count': 5, 'creep_time_constant_min_s': 0.05,
              'creep_time_constant_max_s': 20.0},
    'eddy': {'eddy_time_constant_s': 0.004},
    'thermal': {'thermal_gain_m_per_a2': 2e-6, 'thermal_time_constant_s': 2.0},
    'thermal_negative': {'thermal_gain_m_per_a2': -1.5e-6, 'thermal_time_constant_s': 0.7},
    'dead_time': {'dead_time_s': 0.0137},
    'all': {'creep_gain': 0.05, 'eddy_time_constant_s': 0.005, 'thermal_gain_m_per_a2': 2e-6,
            'thermal_time_constant_s': 3.0, 'dead_time_s': 0.0035, 'noise_std_m': 1e-8,
            'sensor_zero_current_a': 0.2, 'sensor_zero_peak_current_a': 1.8,
            'sensor_offset_m': 1e-6, 'relay_grid_size': 101},
}
SEED = 5
#: Chunk boundaries of the streamed run of the 'all' case.
CUTS = (0, 1, 2, 19, 700, 701, 1501)


def main() -> None:
    """Write the reference file beside this script."""
    t, x = identification_excitation(
        6.0, sample_rate=250.0, seed=3, hold_duration=1.0)
    t = t + 3e-4 * np.sin(7 * t)                          # non-uniform sampling
    arrays = {'time': t, 'current': x, 'cases': np.array(json.dumps(CASES)),
              'cuts': np.array(CUTS)}
    for name, config in CASES.items():
        arrays[name] = MagnetostrictiveActuator(ActuatorConfig(**config),
                                                seed=SEED).simulate(t, x)
    act = MagnetostrictiveActuator(ActuatorConfig(**CASES['all']), seed=SEED)
    arrays['all_streamed'] = np.concatenate([act.advance(t[a:b], x[a:b])
                                             for a, b in zip(CUTS[:-1], CUTS[1:])])
    np.savez_compressed(Path(__file__).with_name('actuator_reference.npz'), **arrays)


if __name__ == '__main__':
    main()
