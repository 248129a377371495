#include <fcntl.h>
#include <unistd.h>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>
static double now(){return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();}
int main(int argc,char**argv){
  std::string dir=argv[1]; size_t mb=atoi(argv[2]); std::string mode=argv[3]; size_t chunk=(argc>4?atoi(argv[4]):8)<<20;
  size_t n=mb<<20; std::vector<char> buf(n); for(size_t i=0;i<n;i++) buf[i]=char(i*7);
  std::string path=dir+"/wb.tmp";
  double t0=now();
  int fd=open(path.c_str(),O_WRONLY|O_CREAT|O_TRUNC,0644);
  size_t done=0; double tw=0;
  while(done<n){ size_t len=std::min(chunk,n-done); ssize_t w=write(fd,buf.data()+done,len); if(w<=0){perror("write");return 1;}
    if(mode=="range"){ sync_file_range(fd,done,w,SYNC_FILE_RANGE_WRITE); if(done>=chunk) sync_file_range(fd,done-chunk,chunk,SYNC_FILE_RANGE_WAIT_BEFORE|SYNC_FILE_RANGE_WRITE|SYNC_FILE_RANGE_WAIT_AFTER);}
    if(mode=="range_nowait"){ sync_file_range(fd,done,w,SYNC_FILE_RANGE_WRITE);}
    done+=w; }
  double t1=now();
  if(mode!="nosync") fsync(fd);
  double t2=now(); close(fd); rename(path.c_str(),(path+"2").c_str()); double t3=now();
  printf("%-13s %4zu MB chunk %2zu MB: write %.3f fsync %.3f close+rename %.3f total %.3f\n",mode.c_str(),mb,chunk>>20,t1-t0,t2-t1,t3-t2,t3-t0);
  unlink((path+"2").c_str());
  return 0;
}
