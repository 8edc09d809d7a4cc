"""Render delegate: moderngl resources and the four passes (skin, crush, relax, draw).

Nothing here imports pxr: it sees only the numpy records of usdwrinkle.scene.
"""
