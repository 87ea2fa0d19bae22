"""Closed-loop work that needs both the structural synthesis (`fdi_analysis`) and the simulator: threshold
calibration on fault-free drives, the screening of every candidate test's practical detectability, the
fault-size sweep, the generated residuals computed on a CAN log, and the kinematic table's calibration. CLI:
``fdi-tune``."""
