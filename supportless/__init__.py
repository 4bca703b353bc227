"""supportless: re-pose a rigged model so it prints with less support."""
