"""Outputs: images (OpenImageIO) and, later, USD layers. Every file is written atomically."""
