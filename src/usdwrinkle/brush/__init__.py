"""The paint brush's geometry, in numpy alone (no Qt, no GL, no stage): what a stamp does
to q (stamp.py: the brush's settings, its modes and falloffs, strokes, flood), and how
the view turns pixels into rays and back (view.py: the orbit camera, picking,
projection). The paint session (app/paint_session.py) and the window (paint/) use it."""
