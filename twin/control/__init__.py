"""Control of the bench: loop design (python-control) and the discrete controllers used in the compiled loop."""
