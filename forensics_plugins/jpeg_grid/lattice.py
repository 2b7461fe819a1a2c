"""Where the main grid's quantisation is missing: blocks whose DCT coefficients are off its lattice.

A JPEG decoder outputs, block by block on its grid, the inverse DCT of
coefficients that are integer multiples of the quantisation steps ``Q_k``.
Once decoded, the pixels keep that lattice: the DCT of a block on the same
grid gives back ``Q_k m + e`` with ``e`` the rounding of the pixels (and of
the colour conversion), a fraction of a grey level. Saved again losslessly,
every block of the photo keeps the lattice; saved again as JPEG with steps
``q_k`` on the same grid (aligned double compression), every value is moved by
at most ``q_k / 2`` more. A piece that never went through that compression
(pasted from a photo of another size or position, painted, cloned off the
block grid) has coefficients anywhere between lattice points. That is the
physical trace ZERO's "missing grid" looks for (Nikoukhah et al. 2021, with
its re-compression at quality 99); read on the lattice itself, the test's
null does not depend on the scene's texture, noise or the camera's quality:
only rounding and clipping move an untouched block off its lattice.

Steps. (1) The DCT of every block on the main grid (``block_coefficients``).
(2) Per low frequency, the step of an earlier lattice, if any: a step
whose lattice holds at least 80 % of the coefficients, significantly more
than the same histogram smoothed over one step would put near it
(``estimate_steps``; Fan & de Queiroz 2003 estimate steps from the same
periodicity). (3) Per block, how many of its informative coefficients lie
off the lattice; a block is flagged when at least two and at least half do
(``off_lattice``). (4) Regions: square windows of blocks holding more
flagged blocks than blocks of the same brightness and detail elsewhere in
the photo, tested a-contrario with the photo's own overdispersion
(``missing_regions``).

References
----------
T. Nikoukhah, J. Anger, M. Colom, J.-M. Morel, R. Grompone von Gioi, ZERO: a Local JPEG Grid Origin Detector
Based on the Number of DCT Zeros and its Applications in Image Forensics, IPOL 11 (2021), pp. 396-433.
Z. Fan, R. L. de Queiroz, Identification of bitmap compression history: JPEG detection and quantizer
estimation, IEEE Trans. Image Processing 12(2), 2003, pp. 230-235.
T. Bianchi, A. Piva, Image forgery localization via block-grained analysis of JPEG artifacts, IEEE Trans.
Information Forensics and Security 7(3), 2012, pp. 1003-1017.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from forensics_core import box_sums

from .nfa import log10_binomial_tail
from .zeros import dct_matrix

# Frequencies with u + v <= 5 (21 of 64, DC included): the ones most often
# quantised coarsely enough to show a lattice and non-zero in textured blocks.
# Only the first LOW rows and columns of the DCT are computed.
LOW = 6
FREQUENCIES = np.add.outer(np.arange(LOW), np.arange(LOW)) <= 5
_D = dct_matrix()[:LOW].astype(np.float32)
# Pixel rounding alone is uniform on +-0.5 grey level, 0.29 per orthonormal
# DCT coefficient; the colour conversion's rounding adds about as much.
ROUNDING_SIGMA = 0.45
TOL_SIGMAS = 3.0
MAX_STEP = 100
# A lattice is accepted for a frequency when it holds at least this share of
# the coefficients large enough to test it. In a photo compressed twice, an
# untouched area keeps the earlier lattice on every coefficient but for
# rounding; single-compressed camera JPEGs and web photos processed after
# their first compression (tone curves, filters) show lattices holding 60-80 %
# of them, by chance or in damaged form, and those must not be read as
# evidence. The price: a manipulated piece over about a fifth of the photo
# hides the lattice it would be tested against.
MIN_ON_SHARE = 0.8
# It must also stand this many standard deviations above a smooth spread of the same values,
MIN_Z = 10.0
# and a smooth spread may put at most this share near it (the step is large
# enough against the rounding to tell lattice from chance).
MAX_CHANCE_SHARE = 0.45
MIN_FREQUENCIES = 3
SAMPLE = 20000
MIN_REGION_BLOCKS = 4
# Window sides in blocks (32 to 1024 pixels).
WINDOW_SIDES = (4, 8, 16, 32, 64, 128)


@dataclass(frozen=True)
class Lattice:
    """The quantisation lattice found on the main grid.

    Attributes
    ----------
    steps : ndarray, shape (8, 8), int
        Step per frequency (natural order), 0 where none was found.
    tolerance : ndarray, shape (8, 8), float
        Largest distance from a lattice point, in DCT units, still on it.
    z : ndarray, shape (8, 8), float
        Strength of each accepted lattice (standard deviations above chance).
    share : ndarray, shape (8, 8), float
        Share of the tested coefficients on each accepted lattice.
    """

    steps: np.ndarray
    tolerance: np.ndarray
    z: np.ndarray
    share: np.ndarray

    @property
    def n_frequencies(self) -> int:
        return int((self.steps > 0).sum())


@dataclass(frozen=True)
class OffLattice:
    """Per-block counts of informative coefficients and of those off the lattice.

    Attributes
    ----------
    informative, off : ndarray, shape (h, w), int
        Blocks on the main grid, row-major from its origin.
    testable : ndarray, shape (h, w), bool
        Blocks without a clipped pixel and with at least two informative coefficients.
    flagged : ndarray, shape (h, w), bool
        Testable blocks with at least two, and at least half, of their informative coefficients off.
    """

    informative: np.ndarray
    off: np.ndarray
    testable: np.ndarray
    flagged: np.ndarray


@dataclass(frozen=True)
class MissingRegion:
    """A connected group of off-lattice blocks.

    Attributes
    ----------
    blocks : ndarray, shape (h, w), bool
        Its blocks (flagged ones and those the closing joined them through).
    n_testable, n_flagged : int
        Testable blocks in it, and flagged ones among them.
    log10_nfa : float
    """

    blocks: np.ndarray
    n_testable: int
    n_flagged: int
    log10_nfa: float


def block_coefficients(y: np.ndarray, origin: tuple[int, int]) -> np.ndarray:
    """Low frequencies of the orthonormal 8x8 DCT of ``y - 128`` on the blocks of the grid at ``origin``.

    Parameters
    ----------
    y : ndarray, shape (H, W)
        Grey levels 0-255.
    origin : (dx, dy)
        Grid origin in pixels, 0-7 each.

    Returns
    -------
    ndarray, shape (h, w, LOW, LOW), float32
        ``h = (H - dy) // 8``, ``w = (W - dx) // 8``; coefficient ``(u, v)``
        (vertical, horizontal frequency) for ``u, v < LOW``, with the JPEG
        standard's level shift and DCT (ITU-T T.81, A.3.3), so a JPEG's
        dequantised coefficients come back as they were (to 1e-4 in float32).
    """
    dx, dy = origin
    h, w = (y.shape[0] - dy) // 8, (y.shape[1] - dx) // 8
    b = np.asarray(y[dy: dy + 8 * h, dx: dx + 8 * w], dtype=np.float32).reshape(h, 8, w, 8).transpose(0, 2, 1, 3)
    return _D @ (b - np.float32(128.0)) @ _D.T


def block_any(mask: np.ndarray, origin: tuple[int, int], shape: tuple[int, int]) -> np.ndarray:
    """Blocks of the grid at ``origin`` (``shape`` = (h, w) blocks) holding a True pixel of ``mask``."""
    dx, dy = origin
    h, w = shape
    return mask[dy: dy + 8 * h, dx: dx + 8 * w].reshape(h, 8, w, 8).any(axis=(1, 3))


def _chance_share(mag: np.ndarray, steps: np.ndarray, tol: float, grain: float) -> np.ndarray:
    """Share of the tested values a step's lattice would hold if their histogram had no period of that step.

    The histogram of ``mag`` (on its grain: the file's own step for a JPEG,
    a quarter grey level otherwise), from ``step / 2`` up, is averaged over
    a sliding window one step long, which removes a period of that step and
    keeps the decay of DCT magnitudes and any irregularity of a single
    compression's histogram (Fan & de Queiroz 2003 compare a histogram with
    its smoothed self in the same way). The returned share is the smoothed
    histogram's mass within ``tol`` of the lattice.

    Parameters
    ----------
    mag : ndarray, shape (N,)
        Coefficient magnitudes.
    steps : ndarray, shape (S,)
        Candidate steps.
    tol : float
        Distance to a lattice point still on it.
    grain : float
        Spacing of the values (0: continuous).

    Returns
    -------
    ndarray, shape (S,)
    """
    g = grain if grain > 0 else 0.25
    idx = np.round(mag / g).astype(np.int64)
    # Zeros past the largest value, so that a window one step long always fits.
    hist = np.bincount(idx, minlength=idx.max(initial=0) + int(np.ceil(steps.max() / g)) + 2).astype(np.float64)
    x = np.arange(hist.size) * g
    out = np.ones(steps.size)
    for i, q in enumerate(steps):
        width = max(1, int(round(q / g)))
        smooth = np.convolve(hist, np.ones(width) / width, mode="same")
        keep = x >= q / 2.0
        near = np.abs(x - q * np.round(x / q)) <= tol
        total = smooth[keep].sum()
        if total > 0:
            out[i] = smooth[keep & near].sum() / total
    return out


def estimate_steps(coef: np.ndarray, usable: np.ndarray, file_steps: np.ndarray | None,
                   sigma: float = ROUNDING_SIGMA) -> Lattice:
    """Per frequency, the step of a lattice most of the photo's coefficients sit on, if any.

    Parameters
    ----------
    coef : ndarray, shape (h, w, LOW, LOW)
        From :func:`block_coefficients`.
    usable : ndarray, shape (h, w), bool
        Blocks without clipped pixels.
    file_steps : ndarray, shape (8, 8), or None
        For a JPEG file, its own luminance steps ``q``: the earlier lattice
        sought must be coarser, and each value may be moved ``q / 2`` off it
        by the file's own rounding. None for a file stored losslessly.
    sigma : float
        Rounding noise per coefficient, DCT units.

    Returns
    -------
    Lattice
    """
    steps = np.zeros((8, 8), int)
    z = np.zeros((8, 8))
    on_share = np.zeros((8, 8))
    tolerance = np.zeros((8, 8))
    values = coef[usable]
    for u, v in zip(*np.nonzero(FREQUENCIES)):
        c = values[:, u, v].astype(np.float64)
        if c.size > SAMPLE:
            c = c[:: c.size // SAMPLE + 1]
        q = float(file_steps[u, v]) if file_steps is not None else 0.0
        tol = q / 2.0 + TOL_SIGMAS * sigma
        tolerance[u, v] = tol
        candidates = np.arange(max(2, int(math.floor(2.0 * tol)) + 1), MAX_STEP + 1, dtype=np.float64)
        if q > 0:
            candidates = candidates[candidates > q]
        if candidates.size == 0:
            continue
        mag = np.abs(c)
        tested = mag[None, :] >= candidates[:, None] / 2.0
        n = tested.sum(axis=1)
        ok = n >= 100
        if not ok.any():
            continue
        candidates, tested, n = candidates[ok], tested[ok], n[ok]
        dist = np.abs(mag[None, :] - candidates[:, None] * np.round(mag[None, :] / candidates[:, None]))
        on = ((dist <= tol) & tested).sum(axis=1)
        chance = _chance_share(mag, candidates, tol, q)
        share = on / n
        zz = (on - n * chance) / np.sqrt(n * chance * (1.0 - chance) + 1e-12)
        good = (share >= MIN_ON_SHARE) & (chance <= MAX_CHANCE_SHARE) & (zz >= MIN_Z)
        if good.any():
            best = int(np.argmax(np.where(good, zz, -np.inf)))
            steps[u, v] = int(candidates[best])
            z[u, v] = float(zz[best])
            on_share[u, v] = float(share[best])
    return Lattice(steps=steps, tolerance=np.where(steps > 0, tolerance, 0.0), z=z, share=on_share)


def off_lattice(coef: np.ndarray, lattice: Lattice, usable: np.ndarray) -> OffLattice:
    """Count, per block, informative coefficients and those off the lattice.

    A coefficient is informative when it is farther than the tolerance from
    zero (near zero it sits on the lattice whether or not the block was
    compressed) and off when it is farther than the tolerance from every
    lattice point.

    Parameters
    ----------
    coef : ndarray, shape (h, w, LOW, LOW)
    lattice : Lattice
    usable : ndarray, shape (h, w), bool

    Returns
    -------
    OffLattice
    """
    sel = lattice.steps[:LOW, :LOW] > 0
    c = coef[:, :, sel].astype(np.float64)
    q = lattice.steps[:LOW, :LOW][sel].astype(np.float64)
    tol = lattice.tolerance[:LOW, :LOW][sel]
    informative = np.abs(c) > tol
    off = informative & (np.abs(c - q * np.round(c / q)) > tol)
    n_inf = informative.sum(axis=2)
    n_off = off.sum(axis=2)
    testable = usable & (n_inf >= 2)
    flagged = testable & (n_off >= 2) & (2 * n_off >= n_inf)
    return OffLattice(informative=n_inf, off=n_off, testable=testable, flagged=flagged)


def expected_flags(counts: OffLattice, brightness: np.ndarray) -> np.ndarray:
    """Per testable block, the share of flagged blocks among the photo's blocks of its kind.

    A block's kind is its mean grey level (eight bins) and its number of
    informative coefficients (2-3, 4-7, 8 or more). Processing applied to the
    whole photo after its compression (a tone curve, a brightness or contrast
    change) moves coefficients off the lattice at a rate that depends on both:
    on the slope of the curve at that grey level and on how large the
    coefficients are. Comparing a region with the blocks of its own kind keeps
    such global processing from passing for a local one. One flagged and one
    unflagged block are added to each kind so that a kind seen a few times
    does not give a rate of 0.

    Parameters
    ----------
    counts : OffLattice
    brightness : ndarray, shape (h, w)
        Mean grey level of each block, 0-255.

    Returns
    -------
    ndarray, shape (h, w), float
        Rate for each testable block, 0 elsewhere.
    """
    level = np.clip(brightness // 32, 0, 7).astype(int)
    size = np.digitize(counts.informative, [4, 8])
    kind = level * 3 + size
    t = counts.testable
    n = np.bincount(kind[t], minlength=24)
    k = np.bincount(kind[t], weights=counts.flagged[t], minlength=24)
    rate = (k + 1.0) / (n + 2.0)
    return np.where(t, rate[kind], 0.0)


def _overdispersion(k: np.ndarray, n: np.ndarray, e: np.ndarray) -> float | None:
    """Variance of window counts about their expectation, in units of the binomial's, robustly; None if too few.

    Untouched areas of a real photo differ from one another more than
    independent blocks would (processing after compression, content the
    covariates miss); the median absolute deviation of the windows'
    standardised counts measures it on the photo itself, and a manipulated
    piece covering less than half the windows does not move it.
    """
    ok = n >= 2.0 * MIN_REGION_BLOCKS
    if ok.sum() < 10:
        return None
    p = e[ok] / n[ok]
    z = (k[ok] - e[ok]) / np.sqrt(np.maximum(n[ok] * p * (1.0 - p), 1e-9))
    mad = 1.4826 * float(np.median(np.abs(z - np.median(z))))
    return max(1.0, mad) ** 2


def missing_regions(counts: OffLattice, brightness: np.ndarray) -> list[MissingRegion]:
    """Square windows of blocks holding significantly more flagged blocks than blocks of their kind do.

    Every square of ``s`` blocks a side, ``s`` = 4, 8, 16, ..., its corners
    ``s / 2`` blocks apart, is one test: its count of flagged blocks among
    its ``n`` testable ones against ``B(n, p)``, ``p`` the mean over those
    blocks of the photo's rate of flagged blocks of their kind
    (:func:`expected_flags`; the photo's own rates, so a large manipulated
    piece only makes the test more cautious). The binomial tail bounds that
    of a sum of unequal Bernoulli variables past its mean plus one
    (Hoeffding 1956). The number of tests is the number of windows, fixed by
    the photo's size before any count is looked at. Meaningful windows that
    overlap or touch are merged into one region, which keeps the NFA of its
    best window.

    Parameters
    ----------
    counts : OffLattice
    brightness : ndarray, shape (h, w)
        Mean grey level of each block.

    Returns
    -------
    list of MissingRegion
        Merged meaningful windows, strongest first, or the single strongest
        window when none is meaningful.

    References
    ----------
    W. Hoeffding, On the distribution of the number of successes in independent trials, Annals of Mathematical
    Statistics 27(3), 1956, pp. 713-721.
    A. Desolneux, L. Moisan, J.-M. Morel, From Gestalt Theory to Image Analysis, Springer, 2008.
    """
    flagged, testable = counts.flagged, counts.testable
    if not testable.any() or not flagged.any():
        return []
    rate = expected_flags(counts, brightness)
    h, w = flagged.shape
    grids = []
    for s in WINDOW_SIDES:
        if s > min(h, w):
            break
        k, n, e = (box_sums(a.astype(np.float64), s, s // 2) for a in (flagged, testable, rate))
        phi = _overdispersion(k, n, e)
        if phi is not None:
            grids.append((s, k, n, e, phi))
    if not grids:
        return []
    log_nt = math.log10(sum(k.size for _, k, _, _, _ in grids))
    windows = []
    for s, k, n, e, phi in grids:
        for i, j in zip(*np.nonzero(k >= MIN_REGION_BLOCKS)):
            p = float(e[i, j]) / max(float(n[i, j]), 1.0)
            lg = log10_binomial_tail(n[i, j] / phi, p * n[i, j] / phi + (k[i, j] - e[i, j]) / phi, p)
            windows.append((log_nt + (lg if math.isfinite(lg) else -1000.0), s, i * (s // 2), j * (s // 2)))
    if not windows:
        return []
    windows.sort()
    hits = [x for x in windows if x[0] < 0.0] or windows[:1]
    cover = np.zeros((h, w), int)
    best = {}
    for lg, s, r, c in hits:
        cover[r: r + s, c: c + s] = 1
    labels, n_lab = ndimage.label(cover, np.ones((3, 3), bool))
    for lg, s, r, c in hits:
        lab = int(labels[r, c])
        best[lab] = min(best.get(lab, 0.0), lg)
    found = []
    for lab in range(1, n_lab + 1):
        blocks = labels == lab
        found.append(MissingRegion(blocks=blocks, n_testable=int((testable & blocks).sum()),
                                   n_flagged=int((flagged & blocks).sum()), log10_nfa=best.get(lab, 0.0)))
    return sorted(found, key=lambda r: r.log10_nfa)
