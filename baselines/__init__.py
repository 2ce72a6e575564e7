"""usvsim's baselines package."""
