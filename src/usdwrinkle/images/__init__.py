"""Images: the AOVs and EXR channels a frame holds (aovs.py), sRGB (colour.py) and
reading image files (imagefiles.py)."""
