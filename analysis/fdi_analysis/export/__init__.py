"""What the analysis hands to the firmware: the C diagnosis table and residual generators (rendered from named
templates), the thresholds and fault-size files they are made from, and the generator report."""
