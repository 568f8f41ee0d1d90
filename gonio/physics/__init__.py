"""Physics: Earth rate, Sagnac scale factors, table kinematics, triad alignment.

Pure functions on numbers and numpy arrays (numpy, scipy, sympy only); nothing
here reads a file or knows a protocol, a bench or a certificate.
"""
