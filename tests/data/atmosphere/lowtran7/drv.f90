program drv
  implicit none
  integer, parameter :: nwl = 4000
  real :: tx(nwl,63), v(nwl), alam(nwl), trace(nwl), unif(nwl), suma(nwl), irr(nwl,3), sumvv(nwl)
  real :: zm(1), pm(1), tm(1), wm(12)
  integer :: i
  tx = -1; v = -1; sumvv = 0
  zm = 0; pm = 0; tm = 0; wm = 0
  call LWTRN7(.false., nwl, 0., 0., 0., tx, v, alam, trace, unif, suma, irr, sumvv, &
       0, 0, 0, 0, 0, 1, 0, zm, pm, tm, wm, 0., 0., 0., 0.)
  open(20, file='out.txt')
  do i = 1, nwl
    if (v(i) > 0) write(20, '(F9.1,1X,ES14.6,1X,ES14.6)') v(i), tx(i,9), sumvv(i)
  end do
  close(20)
end program
