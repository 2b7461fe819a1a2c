"""PRNU: the sensor's fingerprint, from reference photos of the claimed camera, sought in the evidence."""
