"""The randomized cross-check suite (issue 11): egt against independent references."""
