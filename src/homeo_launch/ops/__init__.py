"""Operations tools apart from the launcher: the bench, the soak, the floor chain, the recovery of bags."""
