"""MuJoCo models judged by physics: the BARN worlds, a Jackal-like base, a 2-D laser (mj_multiRay), arms from URDFs."""
