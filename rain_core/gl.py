"""Moved to ``rain_core.gfx``; kept so ``rain_core.gl.create_headless_context`` and friends stay importable."""

from rain_core.gfx.context import MIN_GL_VERSION, GLUnavailableError, create_headless_context
from rain_core.gfx.shaders import ShaderCompileError, ShaderLibrary, ShaderSource
from rain_core.gfx.targets import ColorView, PingPong, RenderTarget, float_target, fullscreen_triangle
from rain_core.gfx.timing import PassTimer
from rain_core.gfx.uniforms import mat4_bytes, set_uniform, set_uniforms

__all__ = ["MIN_GL_VERSION", "ColorView", "GLUnavailableError", "PassTimer", "PingPong", "RenderTarget",
           "ShaderCompileError", "ShaderLibrary", "ShaderSource", "create_headless_context", "float_target",
           "fullscreen_triangle", "mat4_bytes", "set_uniform", "set_uniforms"]
