"""The collision kernels (numba): every state and edge test the planners' compiled loops and the sphere checker run.

One module per concern, each importing only its neighbours here (and numpy, numba, math):

- :mod:`.fk`: forward kinematics of a flattened kinematic tree, and points placed in joint frames;
- :mod:`.primitives`: signed distances to the scene's primitives (boxes, spheres, cylinders), their bounds, and the
  answers of every state test (VALID, COLLIDING, AMBIGUOUS);
- :mod:`.packing`: the robot and scene as the few flat arrays the kernels take;
- :mod:`.grid`: the uniform grid that looks obstacles up in a large scene;
- :mod:`.sphere_scan`: the sphere checker's batch of states (``classify_state``, ``scan_nb``);
- :mod:`.support_bounds`: GJK's separating-axis lower bounds between convex shapes;
- :mod:`.state_validity`: one state down the bounding hierarchy (``classify``), its doubts decided on the shapes;
- :mod:`.bisection` and :mod:`.edge_validity`: an edge's states in coarse-to-fine order, checked one by one.

Nothing is imported here: a module of the package loads numba only when it is itself imported
(:mod:`.bisection` is plain Python, which the exact checker uses).
"""
