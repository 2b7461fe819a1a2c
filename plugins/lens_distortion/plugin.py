"""Hook implementations of the lens distortion detector (filled in by the lens issue)."""
