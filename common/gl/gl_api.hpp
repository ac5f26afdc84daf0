// The OpenGL entry points occswitch uses, loaded at run time through the context's
// get-proc-address (eglGetProcAddress / OSMesaGetProcAddress) into one table per context.
// Nothing calls gl* symbols directly: with libEGL and libOSMesa both linked, link order would
// otherwise decide which library answers. Types and enums come from <GL/glcorearb.h> without
// GL_GLEXT_PROTOTYPES, so it declares no functions. Requires an OpenGL 4.5 core context
// (glClipControl, direct state access, multi-draw indirect, shader storage buffers, compute
// shaders and image load/store: the HC depth pyramid, common/gl/hzb_query.hpp).
#pragma once
#include <functional>
#include <string>

#include <GL/glcorearb.h>

namespace occ {

// X(UPPER, Name): member `Name` of type PFNGL<UPPER>PROC, loaded from "gl<Name>".
#define OCC_GL_FUNCTIONS(X)                                   \
  X(GETSTRING, GetString)                                     \
  X(GETINTEGERV, GetIntegerv)                                 \
  X(GETERROR, GetError)                                       \
  X(ENABLE, Enable)                                           \
  X(DISABLE, Disable)                                         \
  X(VIEWPORT, Viewport)                                       \
  X(SCISSOR, Scissor)                                         \
  X(POLYGONOFFSET, PolygonOffset)                             \
  X(CLIPCONTROL, ClipControl)                                 \
  X(DEPTHFUNC, DepthFunc)                                     \
  X(CULLFACE, CullFace)                                       \
  X(FRONTFACE, FrontFace)                                     \
  X(BLENDFUNCSEPARATE, BlendFuncSeparate)                     \
  X(DEPTHMASK, DepthMask)                                     \
  X(COLORMASK, ColorMask)                                     \
  X(CLEARCOLOR, ClearColor)                                   \
  X(CLEARDEPTH, ClearDepth)                                   \
  X(CLEAR, Clear)                                             \
  X(FINISH, Finish)                                           \
  X(FLUSH, Flush)                                             \
  X(PIXELSTOREI, PixelStorei)                                 \
  X(READPIXELS, ReadPixels)                                   \
  X(CREATEFRAMEBUFFERS, CreateFramebuffers)                   \
  X(BINDFRAMEBUFFER, BindFramebuffer)                         \
  X(NAMEDFRAMEBUFFERRENDERBUFFER, NamedFramebufferRenderbuffer) \
  X(NAMEDFRAMEBUFFERREADBUFFER, NamedFramebufferReadBuffer)   \
  X(CHECKNAMEDFRAMEBUFFERSTATUS, CheckNamedFramebufferStatus) \
  X(CREATERENDERBUFFERS, CreateRenderbuffers)                 \
  X(NAMEDRENDERBUFFERSTORAGE, NamedRenderbufferStorage)       \
  X(CREATESHADER, CreateShader)                               \
  X(SHADERSOURCE, ShaderSource)                               \
  X(COMPILESHADER, CompileShader)                             \
  X(GETSHADERIV, GetShaderiv)                                 \
  X(GETSHADERINFOLOG, GetShaderInfoLog)                       \
  X(DELETESHADER, DeleteShader)                               \
  X(CREATEPROGRAM, CreateProgram)                             \
  X(ATTACHSHADER, AttachShader)                               \
  X(LINKPROGRAM, LinkProgram)                                 \
  X(GETPROGRAMIV, GetProgramiv)                               \
  X(GETPROGRAMINFOLOG, GetProgramInfoLog)                     \
  X(DELETEPROGRAM, DeleteProgram)                             \
  X(USEPROGRAM, UseProgram)                                   \
  X(GETUNIFORMLOCATION, GetUniformLocation)                   \
  X(PROGRAMUNIFORM3F, ProgramUniform3f)                       \
  X(PROGRAMUNIFORMMATRIX4FV, ProgramUniformMatrix4fv)         \
  X(CREATEBUFFERS, CreateBuffers)                             \
  X(DELETEBUFFERS, DeleteBuffers)                             \
  X(NAMEDBUFFERSTORAGE, NamedBufferStorage)                   \
  X(NAMEDBUFFERDATA, NamedBufferData)                         \
  X(NAMEDBUFFERSUBDATA, NamedBufferSubData)                   \
  X(COPYNAMEDBUFFERSUBDATA, CopyNamedBufferSubData)           \
  X(BINDBUFFER, BindBuffer)                                   \
  X(CREATEVERTEXARRAYS, CreateVertexArrays)                   \
  X(DELETEVERTEXARRAYS, DeleteVertexArrays)                   \
  X(BINDVERTEXARRAY, BindVertexArray)                         \
  X(VERTEXARRAYVERTEXBUFFER, VertexArrayVertexBuffer)         \
  X(VERTEXARRAYELEMENTBUFFER, VertexArrayElementBuffer)       \
  X(VERTEXARRAYATTRIBFORMAT, VertexArrayAttribFormat)         \
  X(VERTEXARRAYATTRIBIFORMAT, VertexArrayAttribIFormat)       \
  X(VERTEXARRAYATTRIBBINDING, VertexArrayAttribBinding)       \
  X(VERTEXARRAYBINDINGDIVISOR, VertexArrayBindingDivisor)     \
  X(ENABLEVERTEXARRAYATTRIB, EnableVertexArrayAttrib)         \
  X(DRAWARRAYS, DrawArrays)                                   \
  X(CREATETEXTURES, CreateTextures)                           \
  X(DELETETEXTURES, DeleteTextures)                           \
  X(TEXTURESTORAGE2D, TextureStorage2D)                       \
  X(TEXTURESUBIMAGE2D, TextureSubImage2D)                     \
  X(GENERATETEXTUREMIPMAP, GenerateTextureMipmap)             \
  X(BINDTEXTUREUNIT, BindTextureUnit)                         \
  X(CREATESAMPLERS, CreateSamplers)                           \
  X(DELETESAMPLERS, DeleteSamplers)                           \
  X(SAMPLERPARAMETERI, SamplerParameteri)                     \
  X(BINDSAMPLER, BindSampler)                                 \
  X(MULTIDRAWELEMENTSINDIRECT, MultiDrawElementsIndirect)     \
  X(CREATEQUERIES, CreateQueries)                             \
  X(DELETEQUERIES, DeleteQueries)                             \
  X(BEGINQUERY, BeginQuery)                                   \
  X(ENDQUERY, EndQuery)                                       \
  X(GETQUERYOBJECTUI64V, GetQueryObjectui64v)                 \
  X(NAMEDFRAMEBUFFERTEXTURE, NamedFramebufferTexture)         \
  X(TEXTUREPARAMETERI, TextureParameteri)                     \
  X(GETTEXTUREIMAGE, GetTextureImage)                         \
  X(PROGRAMUNIFORM1I, ProgramUniform1i)                       \
  X(PROGRAMUNIFORM2I, ProgramUniform2i)                       \
  X(PROGRAMUNIFORM4FV, ProgramUniform4fv)                     \
  X(DISPATCHCOMPUTE, DispatchCompute)                         \
  X(MEMORYBARRIER, MemoryBarrier)                             \
  X(BINDIMAGETEXTURE, BindImageTexture)                       \
  X(BINDBUFFERBASE, BindBufferBase)                           \
  X(GETNAMEDBUFFERSUBDATA, GetNamedBufferSubData)

struct GlApi {
#define OCC_GL_MEMBER(upper, name) PFNGL##upper##PROC name = nullptr;
  OCC_GL_FUNCTIONS(OCC_GL_MEMBER)
#undef OCC_GL_MEMBER

  // Resolves every entry point with getproc("glName"); throws std::runtime_error naming the
  // first one that is missing. Call with the context current.
  void load(const std::function<void*(const char*)>& getproc);
};

}  // namespace occ
