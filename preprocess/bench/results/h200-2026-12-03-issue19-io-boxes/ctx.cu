#include <cuda.h>
#include <cuda_runtime.h>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <chrono>
#include <vector>
#include <unistd.h>
static double now(){return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();}
__global__ void k(float* p, size_t n){size_t i=blockIdx.x*size_t(blockDim.x)+threadIdx.x; if(i<n) p[i]+=1;}
int main(int argc,char**argv){
  const char* mode=argc>1?argv[1]:"normal";
  double t0=now();
  if(!strcmp(mode,"drv")){ cuInit(0); double t1=now(); CUdevice d; cuDeviceGet(&d,0); CUcontext c; cuDevicePrimaryCtxRetain(&c,d); cuCtxSetCurrent(c); double t2=now(); fprintf(stderr,"cuInit %.3f primary ctx %.3f\n",t1-t0,t2-t1); }
  int n=0; cudaGetDeviceCount(&n); double t1=now();
  cudaFree(0); double t2=now();
  size_t bytes=145u<<20; float* d; cudaMalloc(&d,bytes); double t3=now();
  std::vector<char> h(bytes,1); double t4=now();
  cudaMemcpy(d,h.data(),bytes,cudaMemcpyHostToDevice); double t5=now();
  k<<<(bytes/4+255)/256,256>>>(d,bytes/4); cudaDeviceSynchronize(); double t6=now();
  fprintf(stderr,"%s: count %.3f ctx %.3f malloc %.3f host %.3f h2d %.3f kernel %.3f\n",mode,t1-t0,t2-t1,t3-t2,t4-t3,t5-t4,t6-t5);
  if(!strcmp(mode,"_exit")){ fflush(stderr); _exit(0);}
  if(!strcmp(mode,"free_exit")){ cudaFree(d); fflush(stderr); _exit(0);}
  if(!strcmp(mode,"reset")){ double a=now(); cudaDeviceReset(); fprintf(stderr,"reset %.3f\n",now()-a);}
  return 0;
}
