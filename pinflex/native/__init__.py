"""Arms held in memory, in and out of pinflex.

Descriptions of Pinocchio models, example-robot-data arms and Python specifications of
flexible links (``robots.py``, ``urdf.py``, ``spec.py``), and linear models exported from a
flexible model (``export.py``). The flexible models themselves are built in
:mod:`pinflex.erls` (``FlexibleModel.from_pinocchio``, ``example_robot``).
"""
