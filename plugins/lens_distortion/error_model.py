"""The error model of real lines, measured on authentic photos (terms of :mod:`.consistency`'s docstring).

Constants only, so that the detector's declared defaults (:mod:`.spec`) can
state them without importing the numerical code.
"""

#: Model-error sd of every line's k1, normalised units (term 3).
TAU_K1 = 0.0044
#: RMS bow of a world edge about its best straight line, as a fraction of its length (term 3).
BOW_REL = 1.6e-4
#: Degrees of freedom of the Student t of a line's standardised departure (term 5).
DOF = 1.3
#: Regional model-error sd shared by the lines of a compact group, k1 units (term 6).
TAU_REGION = 0.0029
