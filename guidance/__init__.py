"""usvsim's guidance package."""
