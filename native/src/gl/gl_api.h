// The OpenGL 4.3 core entry points the backend uses, loaded through
// eglGetProcAddress: nothing links against libGL, so the library loads on
// machines without any GL, and a missing function is a clear error instead
// of a failed load.
#pragma once
#include <GL/glcorearb.h>

namespace glint::gl {

#define GLINT_GL_FUNCTIONS(X)                                          \
  X(PFNGLGETERRORPROC, GetError)                                       \
  X(PFNGLGETSTRINGPROC, GetString)                                     \
  X(PFNGLGETINTEGERVPROC, GetIntegerv)                                 \
  X(PFNGLGETINTEGER64VPROC, GetInteger64v)                             \
  X(PFNGLFINISHPROC, Finish)                                           \
  X(PFNGLGENTEXTURESPROC, GenTextures)                                 \
  X(PFNGLDELETETEXTURESPROC, DeleteTextures)                           \
  X(PFNGLBINDTEXTUREPROC, BindTexture)                                 \
  X(PFNGLACTIVETEXTUREPROC, ActiveTexture)                             \
  X(PFNGLTEXIMAGE2DPROC, TexImage2D)                                   \
  X(PFNGLTEXSTORAGE2DPROC, TexStorage2D)                               \
  X(PFNGLTEXSUBIMAGE2DPROC, TexSubImage2D)                             \
  X(PFNGLTEXPARAMETERIPROC, TexParameteri)                             \
  X(PFNGLPIXELSTOREIPROC, PixelStorei)                                 \
  X(PFNGLGENFRAMEBUFFERSPROC, GenFramebuffers)                         \
  X(PFNGLDELETEFRAMEBUFFERSPROC, DeleteFramebuffers)                   \
  X(PFNGLBINDFRAMEBUFFERPROC, BindFramebuffer)                         \
  X(PFNGLFRAMEBUFFERTEXTURE2DPROC, FramebufferTexture2D)               \
  X(PFNGLCHECKFRAMEBUFFERSTATUSPROC, CheckFramebufferStatus)           \
  X(PFNGLDRAWBUFFERSPROC, DrawBuffers)                                 \
  X(PFNGLREADBUFFERPROC, ReadBuffer)                                   \
  X(PFNGLREADPIXELSPROC, ReadPixels)                                   \
  X(PFNGLVIEWPORTPROC, Viewport)                                       \
  X(PFNGLSCISSORPROC, Scissor)                                         \
  X(PFNGLENABLEPROC, Enable)                                           \
  X(PFNGLDISABLEPROC, Disable)                                         \
  X(PFNGLCLEARBUFFERFVPROC, ClearBufferfv)                             \
  X(PFNGLDEPTHFUNCPROC, DepthFunc)                                     \
  X(PFNGLDEPTHMASKPROC, DepthMask)                                     \
  X(PFNGLCREATESHADERPROC, CreateShader)                               \
  X(PFNGLSHADERSOURCEPROC, ShaderSource)                               \
  X(PFNGLCOMPILESHADERPROC, CompileShader)                             \
  X(PFNGLGETSHADERIVPROC, GetShaderiv)                                 \
  X(PFNGLGETSHADERINFOLOGPROC, GetShaderInfoLog)                       \
  X(PFNGLDELETESHADERPROC, DeleteShader)                               \
  X(PFNGLCREATEPROGRAMPROC, CreateProgram)                             \
  X(PFNGLATTACHSHADERPROC, AttachShader)                               \
  X(PFNGLDETACHSHADERPROC, DetachShader)                               \
  X(PFNGLLINKPROGRAMPROC, LinkProgram)                                 \
  X(PFNGLGETPROGRAMIVPROC, GetProgramiv)                               \
  X(PFNGLGETPROGRAMINFOLOGPROC, GetProgramInfoLog)                     \
  X(PFNGLDELETEPROGRAMPROC, DeleteProgram)                             \
  X(PFNGLUSEPROGRAMPROC, UseProgram)                                   \
  X(PFNGLGETUNIFORMLOCATIONPROC, GetUniformLocation)                   \
  X(PFNGLUNIFORM1IPROC, Uniform1i)                                     \
  X(PFNGLUNIFORM1FPROC, Uniform1f)                                     \
  X(PFNGLUNIFORM2FPROC, Uniform2f)                                     \
  X(PFNGLUNIFORM3FPROC, Uniform3f)                                     \
  X(PFNGLUNIFORM4IPROC, Uniform4i)                                     \
  X(PFNGLUNIFORM4FPROC, Uniform4f)                                     \
  X(PFNGLUNIFORM1FVPROC, Uniform1fv)                                   \
  X(PFNGLUNIFORM1DVPROC, Uniform1dv)                                   \
  X(PFNGLGENVERTEXARRAYSPROC, GenVertexArrays)                         \
  X(PFNGLDELETEVERTEXARRAYSPROC, DeleteVertexArrays)                   \
  X(PFNGLBINDVERTEXARRAYPROC, BindVertexArray)                         \
  X(PFNGLDRAWARRAYSPROC, DrawArrays)                                   \
  X(PFNGLGENBUFFERSPROC, GenBuffers)                                   \
  X(PFNGLDELETEBUFFERSPROC, DeleteBuffers)                             \
  X(PFNGLBINDBUFFERPROC, BindBuffer)                                   \
  X(PFNGLBINDBUFFERBASEPROC, BindBufferBase)                           \
  X(PFNGLBUFFERDATAPROC, BufferData)                                   \
  X(PFNGLBUFFERSUBDATAPROC, BufferSubData)                             \
  X(PFNGLDISPATCHCOMPUTEPROC, DispatchCompute)                         \
  X(PFNGLDISPATCHCOMPUTEINDIRECTPROC, DispatchComputeIndirect)         \
  X(PFNGLMEMORYBARRIERPROC, MemoryBarrier)                             \
  X(PFNGLBINDIMAGETEXTUREPROC, BindImageTexture)                       \
  X(PFNGLVERTEXATTRIBPOINTERPROC, VertexAttribPointer)                 \
  X(PFNGLVERTEXATTRIBIPOINTERPROC, VertexAttribIPointer)               \
  X(PFNGLENABLEVERTEXATTRIBARRAYPROC, EnableVertexAttribArray)         \
  X(PFNGLDISABLEVERTEXATTRIBARRAYPROC, DisableVertexAttribArray)       \
  X(PFNGLGENRENDERBUFFERSPROC, GenRenderbuffers)                       \
  X(PFNGLDELETERENDERBUFFERSPROC, DeleteRenderbuffers)                 \
  X(PFNGLBINDRENDERBUFFERPROC, BindRenderbuffer)                       \
  X(PFNGLRENDERBUFFERSTORAGEPROC, RenderbufferStorage)                 \
  X(PFNGLFRAMEBUFFERRENDERBUFFERPROC, FramebufferRenderbuffer)

// One table per context; members are named without the gl prefix (gl.Finish()).
struct Api {
#define GLINT_GL_MEMBER(type, name) type name = nullptr;
  GLINT_GL_FUNCTIONS(GLINT_GL_MEMBER)
#undef GLINT_GL_MEMBER
};

}  // namespace glint::gl
