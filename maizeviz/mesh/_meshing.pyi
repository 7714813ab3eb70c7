# The meshing loops built from _meshing.c (setup.py): the module tells its source's hash;
# native.py calls its C functions through ctypes.
source_sha256: str
