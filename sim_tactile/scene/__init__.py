"""The MuJoCo scene of a slide: the plate and the finger whose skin nodes probe it
(:mod:`.model`), the skin's nodes (:mod:`.nodes`) and the closed-form elasticity of the skin
(:mod:`.elastic`)."""
