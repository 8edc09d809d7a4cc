"""Command line: one module per concern, as usdAppUtils has framesArgs/cameraArgs."""
