"""EFG's essential conditions: penalty factors (:mod:`.penalty`), Nitsche's method
(:mod:`.nitsche`, and its coupled step :mod:`.coupled`) and the rigid plate's border of
the tangent (:mod:`.plate`)."""
