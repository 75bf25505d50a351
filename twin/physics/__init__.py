"""Component physics of the bench: one module per component, numba-jitted scalar functions.

Each function is plain math on floats so the compiled simulation loop can call it;
docstrings cite the thesis equation (or the reference) they implement.
"""
