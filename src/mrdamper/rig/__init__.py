"""The virtual MR-damper test rig and the paper's design of experiments (Table II).

* :class:`VirtualRig`: actuator, current driver, sensors and replicate variation around any
  :class:`~mrdamper.models.FittedModel`; ``run(x_command, i_command, seed=...)`` gives an
  :class:`~mrdamper.data.Experiment`.
* :func:`reference_damper`: the shipped calibrated reference dampers.
* :mod:`mrdamper.rig.doe`: :func:`table_ii`, :func:`constant_current_sweep`, :func:`make_record`.
* :mod:`mrdamper.rig.doe_io`: :func:`write_doe`, :func:`write_records`, :func:`read_doe`.
"""

from mrdamper.rig.actuator import ServoActuator
from mrdamper.rig.driver import CurrentDriver
from mrdamper.rig.reference import available_reference_dampers, reference_damper
from mrdamper.rig.sensors import Sensor, SensorSuite
from mrdamper.rig.variation import ReplicateVariation
from mrdamper.rig.virtual_rig import VirtualRig

__all__ = [
    "CurrentDriver",
    "ReplicateVariation",
    "Sensor",
    "SensorSuite",
    "ServoActuator",
    "VirtualRig",
    "available_reference_dampers",
    "reference_damper",
]
