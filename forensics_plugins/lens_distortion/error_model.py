"""The error model of real lines, measured on authentic photos (terms of :mod:`.consistency`'s docstring),
and the distribution of real lenses' distortion.

Constants only, so that the detector's declared defaults (:mod:`.spec`) can
state them without importing the numerical code.
"""

#: Model-error sd of every line's k1, normalised units (term 3).
TAU_K1 = 0.0044
#: RMS bow of a world edge about its best straight line, as a fraction of its length (term 3).
BOW_REL = 1.6e-4
#: Degrees of freedom of the Student t of a line's standardised departure (term 5).
DOF = 1.3
#: Student t (degrees of freedom, location, scale) of real lenses' k1 in the project's convention: the
#: maximum-likelihood fit to the one-term k1 of the 6 390 rectilinear calibrations of lensfun 0.3's
#: database (every lens and focal length, converted with the metadata plugin's ``conversion.predict``
#: for a 3:2 image on the calibration sensor). Half of them lie within +-0.014, 99 % within +-0.16;
#: the fit puts 0.2 % beyond +-0.2 (lensfun: 0.4 %, all barrel ultra-wides). The prior of a pasted
#: piece's lens in :mod:`.regions`.
DONOR_K1_T = (2.21, -0.0013, 0.0157)
#: Photo-level model error of the photo's k1 (the one-term model of :class:`.consistency.OneTermModel`),
#: normalised units, added in quadrature to its structure-jackknife error: what all lines of one photo
#: share and no within-photo scatter reveals (identical window frames bowing alike, ropes sagging
#: alike, a lens with k2 seen only where the lines lie). The restricted-maximum-likelihood spread
#: between photos of one lens, 0.0125, over the one-camera series of the real corpus (27 photos of
#: one phone, 3 of another, Dresden's Nikons at one focal length), measured with the centre prior
#: below (0.0096 with the earlier, looser one); benchmarks/lens_truth.py measures what it gives.
TAU_PHOTO = 0.0125
#: Prior standard deviation of the centre of distortion, normalised units, each axis (both models of
#: :mod:`.consistency`). Measured: the 13 authentic photos of the real corpus whose lines pin the centre within
#: 0.04 scatter about the image centre no more than their errors (maximum-likelihood spread 0.000 across, 0.002
#: down); the calibration camera's principal point lies 0.072 off (OpenCV's calibration in
#: ``calibration/README.md``). With 0.1, a few curved objects (a whale's back and the arches over it) pulled
#: the centre 0.33 away and ``k1`` 6.9 standard errors off lensfun's value. A photo cropped off-centre by more
#: than about this much moves the centre out of the prior's reach (README, Limits).
CENTRE_SD = 0.05
