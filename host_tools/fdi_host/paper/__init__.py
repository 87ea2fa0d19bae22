"""The paper's own results reproduced: ARR3/ARR4 (eq. 8-10) and Fig. 6."""
