"""The browser view (viser): a robot, its scene, plans and base runs in any browser; goals dragged and planned."""
