"""usvsim's learning package."""
