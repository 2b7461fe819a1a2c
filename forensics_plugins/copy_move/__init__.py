"""Copy-move (clone) detection, as a forensics plugin (entry point ``copy_move``).

Pipeline: :mod:`.keypoints` (SIFT keypoints of the photo matched against
themselves with the generalised 2NN test) -> :mod:`.transforms` (pairs of
regions related by one similarity transform, by RANSAC) -> :mod:`.identity`
(is the fine grain of the two regions the same, as a copy's is, or only the
structure, as in a scene that repeats itself?). :mod:`.detector` ties them
together; :mod:`.figures` and :mod:`.section` draw the report; :mod:`.synth`
makes cloned and repetitive test photos.
"""
