"""The numba side of the materials: each model's solver class and its kernels.

Kept apart from the declarations in solver/materials/<name>.py because the scene
schema imports those, and the schema must load without numba (the service
validates scenes without it); a declaration names its solver class here, and the
registry imports it when a run first creates the model.
"""
