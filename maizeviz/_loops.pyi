# The compiled loops built from _loops.c (setup.py): the module tells its source's hash;
# loops.py calls its C functions through ctypes.
source_sha256: str
