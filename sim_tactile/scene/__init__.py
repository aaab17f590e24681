"""The MuJoCo scene of a slide and the skin's elasticity.

- :mod:`.model`: the plate and the finger whose skin nodes probe it, built with MjSpec;
- :mod:`.nodes`: the skin's nodes on the pad's undeformed surface;
- :mod:`.elastic`: the elastic half-space in closed form (Boussinesq, Love's rectangles);
- :mod:`.layered`: a stack of bonded layers on a backing, solved per wave number;
- :mod:`.tractions`: the skin's sliding tractions, their stress at depth and their normal
  deflection;
- :mod:`.spline_grid`: a periodic cubic spline read on a tensor grid of points.
"""
