"""Outputs: images (OpenImageIO) and USD layers of baked wrinkle fields. Every file is
written atomically (atomic.py), and only once it is complete."""
