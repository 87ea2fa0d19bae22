"""Host tools for the ROMO FDI project: the CAN database, the dual-track simulator built from the model file,
fault injection (Table I), CAN logs, and the paper's Fig. 6 (ARR3/ARR4).

Modules: `plant` (model -> compiled plant), `vehicle_sim` (closed-loop drive), `controller` (geometric
zero-slip controller and actuators), `scenario`, `faults`, `sensors`, `dbc`, `e2e`, `canlog`, `arr_paper`,
`fig6`, `plots`, `sim_cli` (the ``fdi-sim`` command).
"""

__all__: list[str] = []
