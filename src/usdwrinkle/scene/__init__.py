"""Scene delegate: reads a Usd.Stage and hands frozen numpy records to the renderer.

Nothing below this package is given a Usd object; GPU code sees only the
records of :mod:`usdwrinkle.scene.records`.
"""
