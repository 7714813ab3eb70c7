# The ray-packet kernel built from _packets.c (setup.py): the module tells its source's hash
# and packet layout; packets.py calls its C functions through ctypes.
source_sha256: str
layout: int
