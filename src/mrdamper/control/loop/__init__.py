"""The loop wing of :mod:`mrdamper.control`: the damper in a closed loop.

``car`` (the quarter car, roads, controllers' data), ``quarter_car`` and ``closed_loop`` (the
compiled loops, ``_quarter_car_kernels`` and ``_closed_loop_kernels``), ``quarter_car_study`` (the
controller comparison), ``fidelity`` (the closed-loop fidelity run), ``fronts`` (gain fronts),
``comfort`` (ISO 2631 weighting) and ``doe_extension`` (the closed-loop DoE extension). Import the
modules; this package re-exports nothing, so that importing one module does not load the rest."""
