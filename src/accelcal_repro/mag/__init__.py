"""The magnetometer beside its peers on the real sessions (the workflow's ``mag`` stage).

:mod:`.peers` (Magneto's Li–Griffiths ellipsoid, Dorveaux's iterative method as
tomisuarez2/MagnetometerCalibration runs it, CK-Explorer's ellipsoid + alignment),
:mod:`.sessions` (the real sessions and their rests), :mod:`.stage` (the tool-independent
figure of merit: the spread of |m| and of the dip; session-to-session scatter against the
standard errors), :mod:`.montecarlo` (error / CRLB of the ellipsoid parameters).
"""
