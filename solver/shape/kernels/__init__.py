"""The numba side of the shape functions: each function's weight kernel.

Kept apart from the declarations in solver/shape/<name>.py because the scene
schema and the summary read those, and they must load without numba (the
service validates scenes without it); `shape.get` imports a kernel module when a
run first asks for it.
"""
