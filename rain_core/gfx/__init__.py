"""The GL side of the core: contexts, shaders, targets, the uniform helper, the texture-unit table, the frame
contract, the renderer (pass order and timing), sun shadows and scene drawing. Simulations never import it."""
