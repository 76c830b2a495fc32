"""Looking at a running plant: the motion log (:mod:`devsim.observe.motion_log`)."""
