"""The paint mode (issue 43): artists paint q and W on the posed mesh and see the folds
change at once, on the engine that renders the shot.

- ``window.py``: the Qt front end (PySide6, ``pip install 'usdwrinkle[paint]'``), a door
  onto the application layer's paint session: ``app/paint_session.py`` (a stage, its edit layer,
  the engine, the brush, undo and save; no Qt), ``brush/stamp.py`` (what a stamp does to q
  and W, numpy) and ``brush/view.py`` (the orbit camera and picking rays, numpy).
"""
