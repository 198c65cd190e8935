;;;; tangled/physics-simd.lisp -- GENERATED from physics.org by 'make tangle'. Do not edit.

;; [[file:../physics.org::#JKM0PY][Which wide instructions this machine offers:1]]
(in-package #:luv-physics)
;; Which wide instructions this machine offers:1 ends here

;; [[file:../physics.org::#R0WS8T][Gathering rows into lanes:1]]
(defmacro row-at (index k l)
  "Entry K+L of the fixnum column INDEX, L a constant folded into the load's address. #R0WS8T"
  `(sb-kernel:data-vector-ref-with-offset ,index ,k ,l))

(defmacro transpose-8 (rows columns)
  "Bind COLUMNS to the 8x8 transpose of the f32.8 values ROWS (a LET* binding list). #R0WS8T"
  (destructuring-bind (r0 r1 r2 r3 r4 r5 r6 r7) rows
    (destructuring-bind (c0 c1 c2 c3 c4 c5 c6 c7) columns
      (let ((tt (loop repeat 8 collect (gensym "T"))) (u (loop repeat 8 collect (gensym "U"))))
        (destructuring-bind (t0 t1 t2 t3 t4 t5 t6 t7) tt
          (destructuring-bind (u0 u1 u2 u3 u4 u5 u6 u7) u
            `((,t0 (sb-simd-avx:f32.8-unpacklo ,r0 ,r1)) (,t1 (sb-simd-avx:f32.8-unpackhi ,r0 ,r1))
              (,t2 (sb-simd-avx:f32.8-unpacklo ,r2 ,r3)) (,t3 (sb-simd-avx:f32.8-unpackhi ,r2 ,r3))
              (,t4 (sb-simd-avx:f32.8-unpacklo ,r4 ,r5)) (,t5 (sb-simd-avx:f32.8-unpackhi ,r4 ,r5))
              (,t6 (sb-simd-avx:f32.8-unpacklo ,r6 ,r7)) (,t7 (sb-simd-avx:f32.8-unpackhi ,r6 ,r7))
              (,u0 (sb-simd-avx::%f32.8-shuffle ,t0 ,t2 #x44)) (,u1 (sb-simd-avx::%f32.8-shuffle ,t0 ,t2 #xEE))
              (,u2 (sb-simd-avx::%f32.8-shuffle ,t1 ,t3 #x44)) (,u3 (sb-simd-avx::%f32.8-shuffle ,t1 ,t3 #xEE))
              (,u4 (sb-simd-avx::%f32.8-shuffle ,t4 ,t6 #x44)) (,u5 (sb-simd-avx::%f32.8-shuffle ,t4 ,t6 #xEE))
              (,u6 (sb-simd-avx::%f32.8-shuffle ,t5 ,t7 #x44)) (,u7 (sb-simd-avx::%f32.8-shuffle ,t5 ,t7 #xEE))
              (,c0 (sb-simd-avx::%f32.8-permute128 ,u0 ,u4 #x20)) (,c1 (sb-simd-avx::%f32.8-permute128 ,u1 ,u5 #x20))
              (,c2 (sb-simd-avx::%f32.8-permute128 ,u2 ,u6 #x20)) (,c3 (sb-simd-avx::%f32.8-permute128 ,u3 ,u7 #x20))
              (,c4 (sb-simd-avx::%f32.8-permute128 ,u0 ,u4 #x31)) (,c5 (sb-simd-avx::%f32.8-permute128 ,u1 ,u5 #x31))
              (,c6 (sb-simd-avx::%f32.8-permute128 ,u2 ,u6 #x31)) (,c7 (sb-simd-avx::%f32.8-permute128 ,u3 ,u7 #x31)))))))))

(defmacro with-rows-8 ((v index k &rest columns) &body body)
  "Run BODY with COLUMNS bound to the eight solver rows of V (velocities or deltas, both eight
floats a row) named by INDEX[K..K+7], as the columns of the 8x8 transpose. #R0WS8T"
  (let ((rows (loop repeat 8 collect (gensym "ROW"))))
    `(let* (,@(loop for r in rows for l from 0
                    collect `(,r (sb-simd-avx:f32.8-aref ,v (solver-row (the index (row-at ,index ,k ,l))))))
            ,@(macroexpand-1 `(transpose-8 ,rows ,columns)))
       (declare (ignorable ,@columns))
       ,@body)))

(defmacro scatter-rows-8 (v index k &rest columns)
  "Store COLUMNS back, transposed, as the eight solver rows of V named by INDEX[K..K+7]. Each
column form is evaluated once: the transpose reads each of its inputs twice. #R0WS8T"
  (let ((rows (loop repeat 8 collect (gensym "ROW")))
        (names (loop repeat 8 collect (gensym "COLUMN"))))
    `(let* (,@(mapcar #'list names columns)
            ,@(macroexpand-1 `(transpose-8 ,names ,rows)))
       ,@(loop for r in rows for l from 0
               collect `(setf (sb-simd-avx:f32.8-aref ,v (solver-row (the index (row-at ,index ,k ,l)))) ,r)))))

(defmacro transpose-4 (rows columns)
  "Bind COLUMNS to the 4x4 transpose of the f32.4 values ROWS (a LET* binding list). #R0WS8T"
  (destructuring-bind (r0 r1 r2 r3) rows
    (destructuring-bind (c0 c1 c2 c3) columns
      (let ((t0 (gensym)) (t1 (gensym)) (t2 (gensym)) (t3 (gensym)))
        `((,t0 (sb-simd-sse::%f32.4-shuffle ,r0 ,r1 #x44)) (,t2 (sb-simd-sse::%f32.4-shuffle ,r0 ,r1 #xEE))
          (,t1 (sb-simd-sse::%f32.4-shuffle ,r2 ,r3 #x44)) (,t3 (sb-simd-sse::%f32.4-shuffle ,r2 ,r3 #xEE))
          (,c0 (sb-simd-sse::%f32.4-shuffle ,t0 ,t1 #x88)) (,c1 (sb-simd-sse::%f32.4-shuffle ,t0 ,t1 #xDD))
          (,c2 (sb-simd-sse::%f32.4-shuffle ,t2 ,t3 #x88)) (,c3 (sb-simd-sse::%f32.4-shuffle ,t2 ,t3 #xDD)))))))

(defmacro with-rows-4 ((v index k &rest columns) &body body)
  "Run BODY with COLUMNS (eight names) bound to the four solver rows of V named by
INDEX[K..K+3], transposed: the first four from the rows' low halves, the rest from the high. #R0WS8T"
  (let ((lo (loop repeat 4 collect (gensym "LO"))) (hi (loop repeat 4 collect (gensym "HI")))
        (at (loop repeat 4 collect (gensym "AT"))))
    ;; each row's place is found once, for both its halves
    `(let* (,@(loop for o in at for l from 0
                    collect `(,o (solver-row (the index (row-at ,index ,k ,l)))))
            ,@(loop for r in lo for o in at
                    collect `(,r (sb-simd-sse:f32.4-aref ,v ,o)))
            ,@(loop for r in hi for o in at
                    collect `(,r (sb-simd-sse::%f32.4-load ,v ,o 4)))
            ,@(macroexpand-1 `(transpose-4 ,lo ,(subseq columns 0 4)))
            ,@(macroexpand-1 `(transpose-4 ,hi ,(subseq columns 4 8))))
       (declare (ignorable ,@columns))
       ,@body)))

(defmacro scatter-rows-4 (v index k &rest columns)
  "Store the eight COLUMNS back, transposed, as the four solver rows of V named by INDEX[K..K+3].
Each column form is evaluated once: the transpose reads each of its inputs twice. #R0WS8T"
  (let ((lo (loop repeat 4 collect (gensym "LO"))) (hi (loop repeat 4 collect (gensym "HI")))
        (names (loop repeat 8 collect (gensym "COLUMN"))) (at (loop repeat 4 collect (gensym "AT"))))
    `(let* (,@(mapcar #'list names columns)
            ,@(macroexpand-1 `(transpose-4 ,(subseq names 0 4) ,lo))
            ,@(macroexpand-1 `(transpose-4 ,(subseq names 4 8) ,hi))
            ;; each row's place is found once, for both its halves
            ,@(loop for o in at for l from 0
                    collect `(,o (solver-row (the index (row-at ,index ,k ,l))))))
       ,@(loop for r in lo for o in at
               collect `(setf (sb-simd-sse:f32.4-aref ,v ,o) ,r))
       ,@(loop for r in hi for o in at
               collect `(sb-simd-sse::%f32.4-store ,r ,v ,o 4)))))

(declaim (inline f32.4-select))
(defun f32.4-select (mask a b)
  "Lane by lane, A where MASK is set and B elsewhere, with SSE's and/andnot/or: the mask stays
in any register. #R0WS8T"
  (let ((m (sb-simd-sse2::f32.4!-from-p128 mask)))
    (sb-simd-sse:f32.4-or (sb-simd-sse:f32.4-and m a) (sb-simd-sse:f32.4-andc1 m b))))
;; Gathering rows into lanes:1 ends here

;; [[file:../physics.org::#W1D3KF][One kernel text, two widths:1]]
(defmacro define-wide-kernels (family width documentation &rest operators
                               &key load store broadcast add sub mul div sqrt gt eq if* or* transpose
                                 max andc1 mask)
  "Define the solver kernels of FAMILY for lanes of WIDTH, described by DOCUMENTATION, which each
kernel's docstring quotes: the operator keywords name the sb-simd functions the width-neutral
operators stand for (MASK, the one that reads a comparison's lanes as floats, bit for bit). #W1D3KF"
  (declare (ignore load store broadcast add sub mul div sqrt gt eq if* or* transpose max andc1 mask))
  ;; the names go where FAMILY was read, whatever package is current when the form is expanded:
  ;; define-impact-copy finds its kernel's text under the kernel's name
  (let* ((home (symbol-package family))
         (name (lambda (stem) (intern (format nil "~A/~A" stem family) home)))
         (ws (funcall name "WARM-START-BLOCKS")) (so (funcall name "SOLVE-BLOCKS"))
         (soi (funcall name "SOLVE-IMPACT-BLOCKS")) (pf (funcall name "PREPARE-FRAMES-BLOCKS"))
         ;; the family's own description, its anchor left to the kernel's
         (says (format nil "~D lanes at a time (~A)" width
                       (string-right-trim " " (subseq documentation 0 (search "#" documentation :from-end t)))))
         (operators (apply #'wide-operators width
                           :scatter (intern (format nil "SCATTER-ROWS-~D" width) home)
                           :movemask (if (= width 8) 'sb-simd-avx:f32.8-movemask 'sb-simd-sse:f32.4-movemask)
                           operators)))
    `(progn
       (define-featured-kernel (,ws :features (:body-contacts :friction :rolling-resistance) :operators ,operators)
           (cbuf v start end)
         ,(format nil "Warm start constraints START..END, a whole number of blocks, ~A. #W1D3KF" says)
         (declare (type constraint-columns cbuf) (type f32-column v) (type index start end) #.+kernel-policy+)
         (wide-warm-start ,width))
       (define-featured-kernel (,so :features (:body-contacts :boxes :friction :rolling-resistance :restitution
                                               :hit-events :contact-events)
                                    :operators ,operators)
           (cbuf v d start end inv-h use-bias elapsed push-max threshold hgx hgy hgz)
         ,(format nil "Solve or relax constraints START..END, a whole number of blocks, ~A. Return END, or the first block that may strike or is armed, left unsolved for solve-handing. #W1D3KF" says)
         (declare (type constraint-columns cbuf) (type f32-column v d) (type index start end)
                  (type single-float inv-h elapsed push-max threshold hgx hgy hgz) #.+kernel-policy+)
         (wide-solve ,width))
       (define-impact-copy ,soi ,so
         ,(format nil "Solve or relax constraints START..END, a whole number of blocks, ~A, bouncing impacts ([[#R3ST1T]]): solve-handing runs it on each block at which the pass ~(~A~) or a variant of it stops. #W1D3KF" says so))
       (define-featured-kernel (,pf :features (:boxes) :operators ,operators) (cbuf start end)
         ,(format nil "Complete the frames and masses of constraints START..END, a whole number of blocks, ~A; compiled without boxes, it has no box velocity to resolve. #W1D3KF" says)
         (declare (type constraint-columns cbuf) (type index start end) #.+kernel-policy+)
         (wide-prepare-frames ,width)))))
;; One kernel text, two widths:1 ends here

;; [[file:../physics.org::#W1DOPS][The lanes' vocabulary:1]]
(eval-when (:compile-toplevel :load-toplevel :execute)
  (defun wide-operators (width &key load store broadcast add sub mul div sqrt gt eq if* or* transpose
                                 max andc1 mask scatter movemask)
    "The macrolet definitions of the width-neutral operators for lanes of WIDTH, each standing for
the sb-simd function (or row macro) its keyword names. #W1DOPS"
    `((w+ (a b) `(,',add ,a ,b)) (w- (a b) `(,',sub ,a ,b)) (w* (a b) `(,',mul ,a ,b))
      (w/ (a b) `(,',div ,a ,b)) (wsqrt (a) `(,',sqrt ,a)) (w> (a b) `(,',gt ,a ,b))
      (w= (a b) `(,',eq ,a ,b)) (wif (m a b) `(,',if* ,m ,a ,b)) (wor (a b) `(,',or* ,a ,b))
      (wc (x) `(,',broadcast ,x))
      ;; three selections in one instruction each, to the bit: (wmax a b) is
      ;; (wif (w> a b) a b), b where the two are equal or either is not a number;
      ;; (wzero-where m b) is (wif m (wc 0.0) b); (wany m), whether some lane of
      ;; the mask M is set, the sign bits of (wif m (wc -1.0) (wc 0.0)) read at once
      (wmax (a b) `(,',max ,a ,b))
      (wzero-where (m b) `(,',andc1 (,',mask ,m) ,b))
      (wany (m) `(not (zerop (,',movemask (,',mask ,m)))))
      ;; a side column ([[#SSMPYW]]) is read from the side block of the block at K
      (@w (column) (if (constraint-side-column-p column)
                       `(,',load (side-floats) (side-base k) ,(constraint-offset column))
                       `(,',load data base ,(constraint-offset column))))
      (@w! (column value) (if (constraint-side-column-p column)
                              `(,',store ,value (side-floats) (side-base k) ,(constraint-offset column))
                              `(,',store ,value data base ,(constraint-offset column))))
      ;; true when some lane of the block has no radius on side b, the only lanes
      ;; whose spin columns may be other than zero ([[#SSMPYW]])
      (some-one-sided () `(if-feature :body-contacts
                            (wany (w= (@w rb) (wc 0.0)))
                            t))
      (st@ (i) `(,',load st 0 ,(* ,width i)))
      ;; moved-gap ([[#PR3PAR]]) in lanes, for the relax pass and the frame pass
      (wgap (ddx ddy ddz elapsed)
        `(w+ (w+ (@w separation) (wdot (,ddx ,ddy ,ddz) ((@w nx) (@w ny) (@w nz))))
             (w* (if-feature :boxes (@w kvn) (wc 0.0)) ,elapsed)))
      (st! (i value) `(,',store ,value st 0 ,(* ,width i)))
      ;; the lane groups: the rows of a block's bodies gathered into lanes, and scattered back
      ;; from them ([[#R0WS8T]])
      (wgather (rows &body body) `(,',transpose ,rows ,@body))
      (wscatter (&rest rows) `(,',scatter ,@rows))
      ;; the three-lane helper: a dot product summed left to right, as the scalar kernels sum it
      (wdot ((a b c) (x y z)) `(w+ (w+ (w* ,a ,x) (w* ,b ,y)) (w* ,c ,z))))))
;; The lanes' vocabulary:1 ends here

;; [[file:../physics.org::#W1DWRM][The warm start in lanes:1]]
(defmacro wide-warm-start (width)
  "The body of the warm start of a wide family whose blocks are WIDTH lanes: its impulses, then
body a's rows, then body b's. Expanded in the template's warm start. #W1DWRM"
  `(with-solver-columns cbuf
     (loop for k of-type index from start below end by ,width do
       (let ((base (constraint-base k)))
         (declare (type index base))
         ;; the impulses first; then body a's rows, then body b's, each gathered,
         ;; pushed and scattered alone: a colour never names a body twice, so the order
         ;; changes no bit, and only six velocities are alive at a time
         (if-feature :friction
           (let* ((l (@w normal-impulse)) (l1 (@w tangent-impulse-1)) (l2 (@w tangent-impulse-2))
                  (px (wdot (l l1 l2) ((@w nx) (@w t1x) (@w t2x))))
                  (py (wdot (l l1 l2) ((@w ny) (@w t1y) (@w t2y))))
                  (pz (wdot (l l1 l2) ((@w nz) (@w t1z) (@w t2z))))
                  (cx (w- (w* l1 (@w t2x)) (w* l2 (@w t1x))))
                  (cy (w- (w* l1 (@w t2y)) (w* l2 (@w t1y))))
                  (cz (w- (w* l1 (@w t2z)) (w* l2 (@w t1z)))))
             ;; the spin impulse, read only for a block with a lane that may have one
             ;; ([[#SSMPYW]]): every other lane's is zero, as is every lane's of the
             ;; blocks that do not read it
             (let ((sp (if (some-one-sided) (@w spin-impulse) (wc 0.0))))
             (symbol-macrolet ((ma (@w ima)) (mb (@w imb)) (ia (@w iia)) (ib (@w iib))
                               (ar (@w ra)) (br (@w rb))
                               (rx (if-feature :rolling-resistance
                                     (w+ (@w rolling-impulse-x) (w* sp (@w nx)))
                                     (w* sp (@w nx))))
                               (ry (if-feature :rolling-resistance
                                     (w+ (@w rolling-impulse-y) (w* sp (@w ny)))
                                     (w* sp (@w ny))))
                               (rz (if-feature :rolling-resistance
                                     (w+ (@w rolling-impulse-z) (w* sp (@w nz)))
                                     (w* sp (@w nz)))))
               ;; each body's three masses are read once, into registers
               (wgather (v body-a k vax vay vaz wax way waz a6 a7)
                 (let ((ma ma) (ia ia) (ar ar))
                   (setf vax (w- vax (w* ma px)) vay (w- vay (w* ma py)) vaz (w- vaz (w* ma pz))
                         wax (w- wax (w* ia (w+ (w* ar cx) rx)))
                         way (w- way (w* ia (w+ (w* ar cy) ry)))
                         waz (w- waz (w* ia (w+ (w* ar cz) rz)))))
                 (wscatter v body-a k vax vay vaz wax way waz (wc 0.0) (wc 0.0)))
               ;; without body contacts body b is the dummy row, which its zero
               ;; masses leave as it is: it is neither gathered nor scattered
               (if-feature :body-contacts
               (wgather (v body-b k vbx vby vbz wbx wby wbz b6 b7)
                 (let ((mb mb) (ib ib) (br br))
                   (setf vbx (w+ vbx (w* mb px)) vby (w+ vby (w* mb py)) vbz (w+ vbz (w* mb pz))
                         wbx (w+ wbx (w* ib (w- rx (w* br cx))))
                         wby (w+ wby (w* ib (w- ry (w* br cy))))
                         wbz (w+ wbz (w* ib (w- rz (w* br cz))))))
                 (wscatter v body-b k vbx vby vbz wbx wby wbz (wc 0.0) (wc 0.0)))))))
         ;; without friction the impulse is along the normal and turns nothing; only
         ;; rolling resistance, when the world has it, turns the bodies
         (let* ((l (@w normal-impulse))
                (px (w* l (@w nx))) (py (w* l (@w ny))) (pz (w* l (@w nz))))
           (wgather (v body-a k vax vay vaz wax way waz a6 a7)
             (let ((ma (@w ima)))
               (setf vax (w- vax (w* ma px)) vay (w- vay (w* ma py)) vaz (w- vaz (w* ma pz))))
             (if-feature :rolling-resistance
               (let ((ia (@w iia)))
                 (setf wax (w- wax (w* ia (@w rolling-impulse-x)))
                       way (w- way (w* ia (@w rolling-impulse-y)))
                       waz (w- waz (w* ia (@w rolling-impulse-z))))))
             (wscatter v body-a k vax vay vaz wax way waz (wc 0.0) (wc 0.0)))
           (if-feature :body-contacts
           (wgather (v body-b k vbx vby vbz wbx wby wbz b6 b7)
             (let ((mb (@w imb)))
               (setf vbx (w+ vbx (w* mb px)) vby (w+ vby (w* mb py)) vbz (w+ vbz (w* mb pz))))
             (if-feature :rolling-resistance
               (let ((ib (@w iib)))
                 (setf wbx (w+ wbx (w* ib (@w rolling-impulse-x)))
                       wby (w+ wby (w* ib (@w rolling-impulse-y)))
                       wbz (w+ wbz (w* ib (@w rolling-impulse-z))))))
             (wscatter v body-b k vbx vby vbz wbx wby wbz (wc 0.0) (wc 0.0))))))))))
;; The warm start in lanes:1 ends here

;; [[file:../physics.org::#W1DGAP][The gap and the rows in lanes:1]]
(defmacro wide-solve-gap ()
  "The gap of each lane of the block at K: in the solve the one its relax pass or the frame pass
kept, in the relax pass the prepared gap moved by the deltas and kept. #W1DGAP"
  `(if biased
       (@w gap)
       (let ((s (wgather (d body-a k dax day daz da3 da4 da5 da6 da7)
                  ;; without body contacts body b is the dummy, whose
                  ;; deltas are zeros
                  (if-feature :body-contacts
                    (wgather (d body-b k dbx dby dbz db3 db4 db5 db6 db7)
                      (wgap (w- dbx dax) (w- dby day) (w- dbz daz) el))
                    (wgap (w- (wc 0.0) dax) (w- (wc 0.0) day) (w- (wc 0.0) daz) el)))))
         (@w! gap s)
         s)))

(defmacro wide-solve-gather ()
  "Gather the velocity rows of both bodies of the block at K into the stage ST: six slots each,
body b's only with body contacts. #W1DGAP"
  `(progn
     (wgather (v body-a k gax gay gaz gwx gwy gwz a6 a7)
       (st! 0 gax) (st! 1 gay) (st! 2 gaz) (st! 3 gwx) (st! 4 gwy) (st! 5 gwz))
     ;; without body contacts body b is the dummy row of every constraint: its
     ;; velocities, mass, inertia and radius are zeros, named here as such, and it is
     ;; neither gathered nor scattered
     (if-feature :body-contacts
     (wgather (v body-b k gbx gby gbz hwx hwy hwz b6 b7)
       (st! 6 gbx) (st! 7 gby) (st! 8 gbz) (st! 9 hwx) (st! 10 hwy) (st! 11 hwz)))))

(defmacro wide-solve-scatter ()
  "Scatter the stage ST back as the velocity rows of the block at K: body b's only with body
contacts. #W1DGAP"
  `(progn
     (wscatter v body-a k (st@ 0) (st@ 1) (st@ 2) (st@ 3) (st@ 4) (st@ 5) (wc 0.0) (wc 0.0))
     (if-feature :body-contacts
       (wscatter v body-b k (st@ 6) (st@ 7) (st@ 8) (st@ 9) (st@ 10) (st@ 11) (wc 0.0) (wc 0.0)))))

(defmacro with-solve-lanes (&body body)
  "Run BODY with the names of the solve: the block's frame columns, masses and arms read from
the block, and the twelve velocities read from the stage; without body contacts body b's are the
dummy's zeros. #W1DGAP"
  `(symbol-macrolet ((x (@w nx)) (y (@w ny)) (z (@w nz))
                     (ma (@w ima)) (mb (if-feature :body-contacts (@w imb) (wc 0.0))) (iam (@w iia))
                     (ibm (if-feature :body-contacts (@w iib) (wc 0.0)))
                     (ar (@w ra)) (br (if-feature :body-contacts (@w rb) (wc 0.0)))
                     (ux (@w t1x)) (uy (@w t1y)) (uz (@w t1z))
                     (qx (@w t2x)) (qy (@w t2y)) (qz (@w t2z))
                     (vax (st@ 0)) (vay (st@ 1)) (vaz (st@ 2)) (wax (st@ 3)) (way (st@ 4)) (waz (st@ 5))
                     (vbx (if-feature :body-contacts (st@ 6) (wc 0.0)))
                     (vby (if-feature :body-contacts (st@ 7) (wc 0.0)))
                     (vbz (if-feature :body-contacts (st@ 8) (wc 0.0)))
                     (wbx (if-feature :body-contacts (st@ 9) (wc 0.0)))
                     (wby (if-feature :body-contacts (st@ 10) (wc 0.0)))
                     (wbz (if-feature :body-contacts (st@ 11) (wc 0.0))))
     ,@body))
;; The gap and the rows in lanes:1 ends here

;; [[file:../physics.org::#W1DNRM][The normal impulse and the bounce in lanes:1]]
(defmacro with-wide-normal-impulse (&body body)
  "Run BODY with the bias, the relative velocity, friction's speeds and the new normal impulse
NEW and its change DL of each lane of the block at K; friction's impulse before the cone waits
in the stage. #W1DNRM"
  `(let* ((positive (w> s (wc 0.0)))
          (bias (if biased
                    (let ((soft (w* (@w bias-rate) s)))
                      (wif positive (w* s ih) (wmax soft cap)))
                    (wmax (w* s ih) (wc 0.0))))
          ;; the relative velocity before the impulses, for the normal part
          ;; and for friction, whose two speeds are found here, before the
          ;; normal impulse, which does not change them
          (dvx (w- vbx vax)) (dvy (w- vby vay)) (dvz (w- vbz vaz))
          (vn (w+ (wdot (dvx dvy dvz) (x y z)) (if-feature :boxes (@w kvn) (wc 0.0))))
          ;; (without friction these are constants nothing reads, and vanish)
          (wx (if-feature :friction (w+ (w* ar wax) (w* br wbx)) (wc 0.0)))
          (wy (if-feature :friction (w+ (w* ar way) (w* br wby)) (wc 0.0)))
          (wz (if-feature :friction (w+ (w* ar waz) (w* br wbz)) (wc 0.0)))
          (vt1 (if-feature :friction
                 (w- (w+ (wdot (dvx dvy dvz) (ux uy uz)) (if-feature :boxes (@w kvt1) (wc 0.0)))
                     (wdot (wx wy wz) (qx qy qz)))
                 (wc 0.0)))
          (vt2 (if-feature :friction
                 (w+ (w+ (wdot (dvx dvy dvz) (qx qy qz)) (if-feature :boxes (@w kvt2) (wc 0.0)))
                     (wdot (wx wy wz) (ux uy uz)))
                 (wc 0.0)))
          ;; the friction impulse before the cone, and its length, need no
          ;; normal impulse either; they wait in the stage, so that no register
          ;; holds them across the impact part
          (staged (if-feature :friction
                    (let* ((n1 (w- (@w tangent-impulse-1) (w* (@w tangent-mass) vt1)))
                           (n2 (w- (@w tangent-impulse-2) (w* (@w tangent-mass) vt2)))
                           (len2 (w+ (w* n1 n1) (w* n2 n2))))
                      (st! 12 n1) (st! 13 n2) (st! 14 len2) (st! 15 (wsqrt len2))
                      t)
                    nil))
          (l (@w normal-impulse))
          (raw (if biased
                   (w- (w- l (w* (w* (@w normal-mass) (wif positive (wc 1.0) (@w mass-scale)))
                                 (w+ vn bias)))
                       (w* (wzero-where positive (@w impulse-scale)) l))
                   (w- l (w* (@w normal-mass) (w+ vn bias)))))
          (new (wmax raw (wc 0.0)))
          (mni (if-feature (:or :restitution :contact-events :hit-events)
                           (@w max-normal-impulse) (wc 0.0)))
          ;; impacts and armed contacts ([[#R3ST1T]]): a block with no lane that
          ;; has not pushed yet and approaches faster than the threshold, and
          ;; none armed, skips them
          (dl (w- new l)))
     (declare (ignorable wx wy wz vt1 vt2 staged mni))
     ,@body))

(defmacro wide-solve-bounce ()
  "The normal impulse to keep, its change and what the contact pushed, as three values: NEW, DL
and NEW where no lane may bounce; the impact part where the pseudo-feature :impact-part is
compiled in; else the end of the pass at this block. #W1DNRM"
  `(if-feature :restitution
     ;; only a lane with restitution is ever armed: a block with none reads
     ;; no armed speed ([[#SSMPYW]]), and no lane of it may strike
     (if (not (wany (w> (@w restitution) (wc 0.0))))
       (values new dl new)
     (let ((armed (@w armed-speed)))
             (if (not (wany
                              ;; lanes that have not pushed: vn, or 0 without
                              ;; restitution; the others: an armed lane's speed
                              ;; times -1e30, below any threshold
                              (w> lower (wif (w= mni (wc 0.0))
                                             (wif (w> (@w restitution) (wc 0.0)) vn (wc 0.0))
                                             (w* armed (wc -1e30))))))
                 (values new dl new)
                 (if-feature :impact-part
                 (let* ((e (@w restitution))
                        (impact-f (wif (w= mni (wc 0.0))
                                       (wif (w> new (wc 0.0))
                                            (wif (w> lower vn)
                                                 (wif (w> e (wc 0.0)) (wc 1.0) (wc 0.0))
                                                 (wc 0.0))
                                            (wc 0.0))
                                       (wc 0.0)))
                        (armed-f (wif positive (wc 0.0) (wif (w> armed (wc 0.0)) (wc 1.0) (wc 0.0))))
                        (impact (w> impact-f (wc 0.0)))
                        (sp (wif positive s (wc 0.0)))
                        (dv (w* (w- (wif (w> mb (wc 0.0)) (wc 1.0) (wc 0.0))
                                    (wif (w> ma (wc 0.0)) (wc 1.0) (wc 0.0)))
                                (wdot (ghx ghy ghz) (x y z))))
                        (half (w* (wc 0.5) dv))
                        (c (if biased (w- vn half) (w+ vn half)))
                        (fall (w* (w* (w* (wc 2.0) dv) sp) ih))
                        (u2 (w- (w* c c) fall))
                        (uc (wif impact (wsqrt (wif (w> u2 (wc 0.0)) u2 (wc 0.0))) armed))
                        (wc2 (w+ (w* (w* e e) (w* uc uc)) fall))
                        (short (w> (wc 0.0) wc2))
                        (root (wsqrt (wif (w> wc2 (wc 0.0)) wc2 (wc 0.0))))
                        (w (if biased (w+ root half) (w- root half)))
                        (kick (w* (@w normal-mass) (w- w vn)))
                        (bounce (w> (wif short (wc 0.0) (wif (w> kick (wc 0.0)) (w+ impact-f armed-f) (wc 0.0)))
                                    (wc 0.0)))
                        (arm (w> (wif short impact-f (wc 0.0)) (wc 0.0))))
                   ;; the events report the approach at impact: times -1 is
                   ;; the exact negation
                   (@w! relative-velocity (wif impact (w* uc (wc -1.0)) (@w relative-velocity)))
                   (@w! armed-speed (wif bounce (wc 0.0) (wif arm uc armed)))
                   (let* ((bump (wif bounce kick (wc 0.0))) (bounced (w> bump (wc 0.0))))
                     (values (wif bounced l new) (wif bounced bump dl) (wif bounced bump new))))
                 ;; a block that may strike or is armed ends the pass
                 ;; here, for solve-handing to run the copy with the
                 ;; impact part on it, as it is: nothing of it has been
                 ;; written but the kept gap, which the copy writes again
                 ;; with the same bits
                 (return-from solve-pass k)))))
     (values new dl new)))
;; The normal impulse and the bounce in lanes:1 ends here

;; [[file:../physics.org::#W1DFRC][Friction, rolling resistance and spin in lanes:1]]
(defmacro wide-solve-friction ()
  "Friction in each lane of the block at K, inside the cone, and the normal and friction
impulses applied to the staged velocities; without friction the normal impulse alone. #W1DFRC"
  `(if-feature :friction
     (symbol-macrolet ((n1 (st@ 12)) (n2 (st@ 13)) (len2 (st@ 14)) (root (st@ 15))
                       (l1 (@w tangent-impulse-1)) (l2 (@w tangent-impulse-2)))
     (let* ((limit (w* (@w friction) new))
            (over (w> len2 (w* limit limit)))
            ;; outside the cone len2 > 0, so no lane divides by zero
            ;; 1 inside the cone, where multiplying by it changes no bit
            (scale (wif over (w/ limit (wif over root (wc 1.0))) (wc 1.0)))
            (n1 (w* n1 scale)) (n2 (w* n2 scale))
            (d1 (w- n1 l1)) (d2 (w- n2 l2)))
       (@w! normal-impulse new)
       (if-feature (:or :restitution :contact-events :hit-events)
         (@w! max-normal-impulse (wmax mni pushed)))
       (@w! tangent-impulse-1 n1) (@w! tangent-impulse-2 n2)
       ;; each velocity takes the normal impulse, then friction's, in one
       ;; expression: the same two roundings as two steps, one store; a
       ;; component at a time, so each frame column is read once
       (let ((madl (w* ma dl)) (mbdl (w* mb dl)) (iar (w* iam ar)) (ibr (w* ibm br))
             (ma ma) (mb mb))
         (declare (ignorable mbdl ibr mb))
         (macrolet ((component (i j k l n u q)
                      `(let* ((u ,u) (q ,q)
                              (p (w+ (w* d1 u) (w* d2 q)))
                              (c (w- (w* d1 q) (w* d2 u))))
                         (st! ,i (w- (w- (st@ ,i) (w* madl ,n)) (w* ma p)))
                         (st! ,k (w- (st@ ,k) (w* iar c)))
                         (if-feature :body-contacts
                           (progn (st! ,j (w+ (w+ (st@ ,j) (w* mbdl ,n)) (w* mb p)))
                                  (st! ,l (w- (st@ ,l) (w* ibr c))))))))
           (component 0 6 3 9 x ux qx) (component 1 7 4 10 y uy qy)
           (component 2 8 5 11 z uz qz)))))
     ;; without friction only the normal impulse moves the bodies
     (progn
       (@w! normal-impulse new)
       (if-feature (:or :restitution :contact-events :hit-events)
         (@w! max-normal-impulse (wmax mni pushed)))
       (let ((madl (w* ma dl)) (mbdl (w* mb dl)))
         (declare (ignorable mbdl))
         (st! 0 (w- (st@ 0) (w* madl x))) (st! 1 (w- (st@ 1) (w* madl y)))
         (st! 2 (w- (st@ 2) (w* madl z)))
         (if-feature :body-contacts
           (progn (st! 6 (w+ (st@ 6) (w* mbdl x))) (st! 7 (w+ (st@ 7) (w* mbdl y)))
                  (st! 8 (w+ (st@ 8) (w* mbdl z)))))))))

(defmacro wide-solve-rolling-resistance ()
  "Rolling resistance in each lane of the block at K, on the staged angular velocities; skipped
by a block none of whose lanes has a rolling limit. #W1DFRC"
  `(if-feature :rolling-resistance
     (let* ((rl (@w rolling-limit))
            (rolling (w> rl (wc 0.0))))
       (when (wany rolling)
         (let* ((rlimit (w* rl new))
                (rm (@w rolling-mass))
                (rx (@w rolling-impulse-x)) (ry (@w rolling-impulse-y)) (rz (@w rolling-impulse-z))
                (nrx (w- rx (w* rm (w- wbx wax)))) (nry (w- ry (w* rm (w- wby way))))
                (nrz (w- rz (w* rm (w- wbz waz))))
                (len2 (wdot (nrx nry nrz) (nrx nry nrz)))
                (over (w> len2 (w* rlimit rlimit)))
                (scale (wif over (w/ rlimit (wsqrt (wif over len2 (wc 1.0)))) (wc 1.0)))
                (nrx (w* nrx scale)) (nry (w* nry scale)) (nrz (w* nrz scale))
                (dx (w- nrx rx)) (dy (w- nry ry)) (dz (w- nrz rz)))
           (@w! rolling-impulse-x (wif rolling nrx rx))
           (@w! rolling-impulse-y (wif rolling nry ry))
           (@w! rolling-impulse-z (wif rolling nrz rz))
           (st! 3 (wif rolling (w- wax (w* iam dx)) wax)) (st! 4 (wif rolling (w- way (w* iam dy)) way))
           (st! 5 (wif rolling (w- waz (w* iam dz)) waz))
           (if-feature :body-contacts
             (progn (st! 9 (wif rolling (w+ wbx (w* ibm dx)) wbx))
                    (st! 10 (wif rolling (w+ wby (w* ibm dy)) wby))
                    (st! 11 (wif rolling (w+ wbz (w* ibm dz)) wbz)))))))))

(defmacro wide-solve-spin-friction ()
  "Spin friction in each lane of the block at K, on the staged angular velocities; skipped by a
block none of whose lanes may have a spin limit. #W1DFRC"
  `(if-feature :friction
     (when (some-one-sided)
     (let* ((sl (@w spin-limit))
            (spinning (w> sl (wc 0.0))))
       (when (wany spinning)
         (let* ((slimit (w* sl new)) (sp (@w spin-impulse))
                (raw (w- sp (w* (@w rolling-mass)
                                (wdot ((w- wbx wax) (w- wby way) (w- wbz waz)) (x y z)))))
                (low (w* slimit (wc -1.0)))
                (nsp (wif (w> raw slimit) slimit (wif (w> low raw) low raw)))
                (ds (w- nsp sp)))
           (@w! spin-impulse (wif spinning nsp sp))
           (st! 3 (wif spinning (w- wax (w* iam (w* ds x))) wax))
           (st! 4 (wif spinning (w- way (w* iam (w* ds y))) way))
           (st! 5 (wif spinning (w- waz (w* iam (w* ds z))) waz))
           (if-feature :body-contacts
             (progn (st! 9 (wif spinning (w+ wbx (w* ibm (w* ds x))) wbx))
                    (st! 10 (wif spinning (w+ wby (w* ibm (w* ds y))) wby))
                    (st! 11 (wif spinning (w+ wbz (w* ibm (w* ds z))) wbz))))))))))
;; Friction, rolling resistance and spin in lanes:1 ends here

;; [[file:../physics.org::#W1DPAS][The solve pass in lanes:1]]
(defmacro wide-solve (width)
  "The body of the solve of a wide family whose blocks are WIDTH lanes: for each block its gap,
its rows gathered, the normal impulse, the bounce, friction, rolling resistance and spin, and its
rows scattered; the value is END, or the block the pass stopped at. #W1DPAS"
  `(block solve-pass
     (let ((st (make-array ,(* 16 width) :element-type 'single-float))
           ;; the scalars, broadcast once: a scalar read back inside the loop would be a
           ;; legacy SSE instruction among the 256-bit ones ([[#F4M1LY]])
           (lower (wc (- threshold))) (ghx (wc hgx)) (ghy (wc hgy)) (ghz (wc hgz)) (ih (wc inv-h))
           (el (wc elapsed)) (cap (wc (- push-max))))
       (declare (dynamic-extent st) (type (simple-array single-float (,(* 16 width))) st)
                (ignorable lower ghx ghy ghz))
       (unswitch-bias (use-bias)
         (with-solver-columns cbuf
           (loop for k of-type index from start below end by ,width do
             (progn
               (let ((base (constraint-base k)))
                 (declare (type index base))
                 (let ((s (wide-solve-gap)))
                   (wide-solve-gather)
                   (with-solve-lanes
                     (with-wide-normal-impulse
                       (multiple-value-bind (new dl pushed) (wide-solve-bounce)
                         (declare (ignorable pushed))
                         (wide-solve-friction)
                         (wide-solve-rolling-resistance)
                         (wide-solve-spin-friction))))
                   (wide-solve-scatter))))))))
     end))
;; The solve pass in lanes:1 ends here

;; [[file:../physics.org::#W1DFRM][The frames in lanes:1]]
(defmacro wide-prepare-frames (width)
  "The body of the frame pass of a wide family whose blocks are WIDTH lanes: tangents, the box
velocity in the frame, the gap and the masses of each lane. #W1DFRM"
  `(with-constraint-block () cbuf
     (loop for k of-type index from start below end by ,width do
       (let ((base (constraint-base k)))
         (declare (type index base))
         (macrolet ((inverse (v)
                      ;; 1/v where v > 0, else 0; the divisor is 1 where v is not, so
                      ;; no lane divides by zero
                      `(let ((pos (w> ,v (wc 0.0))))
                         (wif pos (w/ (wc 1.0) (wif pos ,v (wc 1.0))) (wc 0.0)))))
           (let* ((x (@w nx)) (y (@w ny)) (z (@w nz))
                  ;; |y| > 0.9, as two comparisons
                  (big (wor (w> y (wc 0.9)) (w> (wc -0.9) y)))
                  (zz (w* z z))
                  (q (wif big (w+ zz (w* y y)) (w+ zz (w* x x))))
                  (s (w/ (wc 1.0) (wsqrt (wif (w> q (wc 0.0)) q (wc 1.0)))))
                  (zs (w* z s))
                  ;; times -1: the exact negation, the zero's sign included
                  (ux (wif big (wc 0.0) (w* zs (wc -1.0))))
                  (uy (wif big zs (wc 0.0)))
                  (uz (wif big (w* (w* y s) (wc -1.0)) (w* x s)))
                  (qx (w- (w* y uz) (w* z uy))) (qy (w- (w* z ux) (w* x uz))) (qz (w- (w* x uy) (w* y ux))))
             (@w! t1x ux) (@w! t1y uy) (@w! t1z uz) (@w! t2x qx) (@w! t2y qy) (@w! t2z qz)
             ;; without boxes there is no box velocity to resolve
             (if-feature :boxes
               (let ((kx (@w kvx)) (ky (@w kvy)) (kz (@w kvz)))
                 (@w! kvn (wdot (kx ky kz) (x y z)))
                 (@w! kvt1 (wdot (kx ky kz) (ux uy uz)))
                 (@w! kvt2 (wdot (kx ky kz) (qx qy qz)))))
             (@w! gap (wgap (wc 0.0) (wc 0.0) (wc 0.0) (wc 0.0))))
           (let* ((ra (@w ra)) (rb (@w rb)) (iia (@w iia)) (iib (@w iib))
                  (mass-sum (w+ (@w ima) (@w imb))))
             (@w! normal-mass (inverse mass-sum))
             (@w! tangent-mass (inverse (w+ (w+ mass-sum (w* (w* iia ra) ra)) (w* (w* iib rb) rb))))
             (@w! rolling-mass (inverse (w+ iia iib)))))))))
;; The frames in lanes:1 ends here

;; [[file:../physics.org::#F4M1LY][The SSE and AVX2 families:1]]
(define-wide-kernels avx2 8
  "Eight lanes of AVX2: f32.8 arithmetic, vblendvps selection. #F4M1LY"
  :load sb-simd-avx::%f32.8-load :store sb-simd-avx::%f32.8-store :broadcast sb-simd-avx:f32.8
  :add sb-simd-avx:f32.8+ :sub sb-simd-avx:f32.8- :mul sb-simd-avx:f32.8* :div sb-simd-avx:f32.8/
  :sqrt sb-simd-avx:f32.8-sqrt :gt sb-simd-avx:f32.8> :eq sb-simd-avx:f32.8= :if* sb-simd-avx:f32.8-if
  :or* sb-simd-avx2:u32.8-or :transpose with-rows-8
  :max sb-simd-avx:f32.8-max :andc1 sb-simd-avx:f32.8-andc1 :mask sb-simd-avx::f32.8!-from-p256)

(define-wide-kernels sse 4
  "Four lanes of SSE4.1: f32.4 arithmetic, and/and-not/or selection. #F4M1LY"
  :load sb-simd-sse::%f32.4-load :store sb-simd-sse::%f32.4-store :broadcast sb-simd-sse:f32.4
  :add sb-simd-sse:f32.4+ :sub sb-simd-sse:f32.4- :mul sb-simd-sse:f32.4* :div sb-simd-sse:f32.4/
  :sqrt sb-simd-sse:f32.4-sqrt :gt sb-simd-sse2:f32.4> :eq sb-simd-sse2:f32.4= :if* f32.4-select
  :or* sb-simd-sse2:u32.4-or :transpose with-rows-4
  :max sb-simd-sse:f32.4-max :andc1 sb-simd-sse:f32.4-andc1 :mask sb-simd-sse2::f32.4!-from-p128)

(defclass wide-kernels (scalar-kernels) ()
  (:documentation "A family that solves each colour's blocks in lanes and the overflow colour
with the scalar kernels. #F4M1LY"))
(defclass sse-kernels (wide-kernels) ()
  (:documentation "Four lanes of SSE4.1 f32.4. #F4M1LY"))
(defclass avx2-kernels (wide-kernels) ()
  (:documentation "Eight lanes of AVX2 f32.8. #F4M1LY"))

(defmacro do-colour-runs ((start end world &optional settle) wide-form overflow-form)
  "Run WIDE-FORM for each colour's run START..END of WORLD's constraints, then SETTLE, then
OVERFLOW-FORM for the overflow colour's run. #F4M1LY"
  (let ((starts (gensym)) (c (gensym)))
    `(let ((,starts (physics-world-color-starts ,world)))
       (dotimes (,c +physics-max-colors+)
         (let ((,start (aref ,starts ,c)) (,end (aref ,starts (1+ ,c))))
           (when (< ,start ,end) ,wide-form)))
       ,@(when settle (list settle))
       (let ((,start (aref ,starts +physics-max-colors+)) (,end (aref ,starts (1+ +physics-max-colors+))))
         (when (< ,start ,end) ,overflow-form)))))

(macrolet ((define-family-methods (class width ws so si pf wj sj &optional settle)
             `(progn
                (defmethod physics-prepare-frames ((kernels ,class) world)
                  (let* ((cbuf (physics-world-constraints world))
                         (variant (world-kernel-variant world kernels))
                         (wide (kernel-variant-wide-prepare-frames variant))
                         (narrow (kernel-variant-prepare-frames variant)))
                    (do-colour-runs (s e world ,settle) (funcall wide cbuf s e) (funcall narrow cbuf s e))))
                (defmethod wide-kernel-names ((kernels ,class)) (values ',ws ',so ',pf ',si))
                (defmethod physics-warm-start ((kernels ,class) world)
                  (let* ((cbuf (physics-world-constraints world)) (v (physics-world-velocities world))
                         (variant (world-kernel-variant world kernels))
                         (wide (kernel-variant-wide-warm-start variant))
                         (narrow (kernel-variant-warm-start variant)))
                    ;; each colour's joints before its contacts, point joints in lanes ([[#J0LANE]])
                    (do-constraint-colours (s e world :settle ,settle
                                                      :joints (set (,wj set v (physics-world-deltas world) s e)))
                      (funcall wide cbuf v s e) (funcall narrow cbuf v s e))))
                (defmethod physics-solve-contacts ((kernels ,class) world inv-h use-bias elapsed)
                  (let* ((cbuf (physics-world-constraints world)) (v (physics-world-velocities world))
                         (d (physics-world-deltas world)) (push-max (f32 (physics-world-push-max world)))
                         (variant (world-kernel-variant world kernels))
                         (wide (kernel-variant-wide-solve variant))
                         (narrow (kernel-variant-solve variant)))
                    (multiple-value-bind (threshold hgx hgy hgz) (impact-parameters world)
                      (do-constraint-colours (s e world :settle ,settle
                                                        :joints (set (,sj set v d inv-h use-bias s e)))
                        (solve-handing wide ',si ,width cbuf v d s e inv-h use-bias elapsed push-max threshold hgx hgy hgz)
                        (solve-handing narrow 'solve-impact-range 1
                                       cbuf v d s e inv-h use-bias elapsed push-max threshold hgx hgy hgz))))))))
  (define-family-methods sse-kernels 4 warm-start-blocks/sse solve-blocks/sse solve-impact-blocks/sse
    prepare-frames-blocks/sse warm-start-joints/sse solve-joints/sse)
  ;; after 256-bit code, clear the upper halves of the ymm registers before any legacy SSE
  ;; instruction runs: the scalar code SBCL emits is legacy SSE, and on this CPU it ran three
  ;; times slower for the rest of the step without it
  (define-family-methods avx2-kernels 8 warm-start-blocks/avx2 solve-blocks/avx2 solve-impact-blocks/avx2
    prepare-frames-blocks/avx2 warm-start-joints/avx2 solve-joints/avx2
    (sb-simd-avx:vzeroupper)))

(register-kernel-family :sse 'sse-kernels :sse4.1)
(register-kernel-family :avx2 'avx2-kernels :avx2)

;; the wide kernels of the standard feature sets, compiled with the page ([[#FEAT5X]])
(precompile-featured-kernels (warm-start-blocks/sse solve-blocks/sse prepare-frames-blocks/sse
                              warm-start-blocks/avx2 solve-blocks/avx2 prepare-frames-blocks/avx2))
;; The SSE and AVX2 families:1 ends here

;; [[file:../physics.org::#J0LANE][Point joints in lanes:1]]
(eval-when (:compile-toplevel :load-toplevel :execute)
  (defun joint-lane-operators (&key aref add sub mul broadcast xor gt if* transpose scatter)
    "The macrolet definitions of the joint lanes' operators, each standing for the sb-simd
function (or row macro) its keyword names: J+ J- J*, JC a broadcast, JNEG the sign flipped, J@
and J! a joint column's lanes at row J, JKEEP the new value where a mass is above zero and the
old elsewhere, JGATHER and JSCATTER the solver rows an index column names at J. #J0LANE"
    `((j+ (a b) `(,',add ,a ,b)) (j- (a b) `(,',sub ,a ,b)) (j* (a b) `(,',mul ,a ,b))
      (jc (x) `(,',broadcast ,x))
      (jneg (a) `(,',xor ,a (,',broadcast -0.0)))
      (j@ (column) `(,',aref ,column j))
      (j! (column value) `(setf (,',aref ,column j) ,value))
      (jkeep (mass new old) `(,',if* (,',gt ,mass (,',broadcast 0.0)) ,new ,old))
      (jgather ((v index &rest columns) &body body) `(,',transpose (,v ,index j ,@columns) ,@body))
      (jscatter (v index &rest columns) `(,',scatter ,v ,index j ,@columns)))))

(defmacro wide-joint-push (px py pz)
  "Push the lanes' impulses PX PY PZ (names) on the gathered rows: minus on body a's VAX .. WAZ,
plus on body b's VBX .. WBZ where its mass is above zero, the scalar push! lane by lane.
Expanded within the joint lanes' operators. #J0LANE"
  `(let ((ma (j@ ima)) (ia (j@ iia)) (mb (j@ imb)) (ib (j@ iib)))
     (setf vax (j- vax (j* ma ,px)) vay (j- vay (j* ma ,py)) vaz (j- vaz (j* ma ,pz))
           wax (j- wax (j* ia (j- (j* ay ,pz) (j* az ,py))))
           way (j- way (j* ia (j- (j* az ,px) (j* ax ,pz))))
           waz (j- waz (j* ia (j- (j* ax ,py) (j* ay ,px)))))
     (setf vbx (jkeep mb (j+ vbx (j* mb ,px)) vbx)
           vby (jkeep mb (j+ vby (j* mb ,py)) vby)
           vbz (jkeep mb (j+ vbz (j* mb ,pz)) vbz)
           wbx (jkeep mb (j+ wbx (j* ib (j- (j* by ,pz) (j* bz ,py)))) wbx)
           wby (jkeep mb (j+ wby (j* ib (j- (j* bz ,px) (j* bx ,pz)))) wby)
           wbz (jkeep mb (j+ wbz (j* ib (j- (j* bx ,py) (j* by ,px)))) wbz))))

(defmacro with-joint-block-rows (&body body)
  "Run BODY over the block at J with both bodies' velocity rows gathered from V (VAX .. WAZ and
VBX .. WBZ, with their spare slots), the levers AX .. BZ read, then scatter the rows back.
Expanded within the joint lanes' operators. #J0LANE"
  `(jgather (v row-a vax vay vaz wax way waz a6 a7)
     (jgather (v row-b vbx vby vbz wbx wby wbz b6 b7)
       (let ((ax (j@ rax)) (ay (j@ ray)) (az (j@ raz)) (bx (j@ rbx)) (by (j@ rby)) (bz (j@ rbz)))
         ,@body)
       (jscatter v row-a vax vay vaz wax way waz a6 a7)
       (jscatter v row-b vbx vby vbz wbx wby wbz b6 b7))))

(defmacro wide-point-warm-start ()
  "The warm start of the block of point joints at J: each lane's carried impulse pushed again.
#J0LANE"
  `(with-joint-block-rows
     (let ((px (j@ impulse-x)) (py (j@ impulse-y)) (pz (j@ impulse-z)))
       (wide-joint-push px py pz))))

(defmacro wide-point-impulse (px ix ka kb kc rx ry rz ms is)
  "Bind PX to a lane's impulse along one axis, -(MS (KA RX + KB RY + KC RZ)) - IS IX, the scalar
apply-point's chain. #J0LANE"
  `(,px (j- (jneg (j* ,ms (j+ (j+ (j* (j@ ,ka) ,rx) (j* (j@ ,kb) ,ry)) (j* (j@ ,kc) ,rz))))
            (j* ,is ,ix))))

(defmacro with-lane-separation (biased &body body)
  "Run BODY, when BIASED, with CX CY CZ bound to the lanes' separation of the anchors now, c0 +
(delta b - delta a) + (r b - r a) summed as the scalar text sums it, both bodies' delta rows
gathered from D; else BODY alone, which reads no delta. #J0LANE"
  (if biased
      `(jgather (d row-a dax day daz da3 da4 da5 da6 da7)
         (jgather (d row-b dbx dby dbz db3 db4 db5 db6 db7)
           (let ((cx (j+ (j+ (j@ sx) (j- dbx dax)) (j- bx ax)))
                 (cy (j+ (j+ (j@ sy) (j- dby day)) (j- by ay)))
                 (cz (j+ (j+ (j@ sz) (j- dbz daz)) (j- bz az))))
             ,@body)))
      `(progn ,@body)))

(defmacro wide-point-solve (biased)
  "One push of the block of point joints at J: the anchors' relative velocity, with the bias of
the separation when BIASED (the solve) and rigid without it (the relax), through the prepared
inverse effective mass; the impulses carried and pushed. #J0LANE"
  `(with-joint-block-rows
     (with-lane-separation ,biased
       (let* ((vx (j- (j+ vbx (j- (j* wby bz) (j* wbz by))) (j+ vax (j- (j* way az) (j* waz ay)))))
              (vy (j- (j+ vby (j- (j* wbz bx) (j* wbx bz))) (j+ vay (j- (j* waz ax) (j* wax az)))))
              (vz (j- (j+ vbz (j- (j* wbx by) (j* wby bx))) (j+ vaz (j- (j* wax ay) (j* way ax)))))
              ,@(if biased
                    `((br (j@ bias-rate))
                      (rx (j+ vx (j* br cx))) (ry (j+ vy (j* br cy))) (rz (j+ vz (j* br cz)))
                      (ms (j@ mass-scale)) (is (j@ impulse-scale)))
                    `((rx vx) (ry vy) (rz vz) (ms (jc 1.0)) (is (jc 0.0))))
              (ix (j@ impulse-x)) (iy (j@ impulse-y)) (iz (j@ impulse-z))
              ,(macroexpand-1 `(wide-point-impulse px ix k11 k12 k13 rx ry rz ms is))
              ,(macroexpand-1 `(wide-point-impulse py iy k12 k22 k23 rx ry rz ms is))
              ,(macroexpand-1 `(wide-point-impulse pz iz k13 k23 k33 rx ry rz ms is)))
         (j! impulse-x (j+ ix px)) (j! impulse-y (j+ iy py)) (j! impulse-z (j+ iz pz))
         (wide-joint-push px py pz)))))

(defmacro do-joint-blocks ((width settle) wide-form scalar-form)
  "Run, over the joints START..END of SET, WIDE-FORM for each block of WIDTH point joints at J,
and SCALAR-FORM, SETTLE before it, for each other joint at J: every joint of the overflow colour,
whose joints may share a body, and of a block that holds a distance joint or passes END; SETTLE
again at the end. #J0LANE"
  `(let ((overflow (aref (joint-set-color-starts set) +physics-max-colors+))
         (j start))
     (declare (type index overflow j))
     (loop while (< j end)
           do (if (and (<= (+ j ,width) end) (<= (+ j ,width) overflow)
                       (loop for l of-type index from j below (+ j ,width)
                             always (= (aref kind l) +joint-point+)))
                  (progn ,wide-form (incf j ,width))
                  (progn ,@(when settle (list settle)) ,scalar-form (incf j))))
     ,@(when settle (list settle))))

(defmacro define-joint-lanes (family width documentation settle &rest operators)
  "Define the warm start and the solve of FAMILY's joints, WARM-START-JOINTS/FAMILY and
SOLVE-JOINTS/FAMILY, with the arguments of warm-start-joints and solve-joints: blocks of WIDTH
point joints in lanes of the OPERATORS (joint-lane-operators), described by DOCUMENTATION, which
their docstrings quote, every other joint by the scalar functions, SETTLE before them and at the
end. #J0LANE"
  (let* ((says (string-right-trim " " (subseq documentation 0 (search "#" documentation :from-end t))))
         (home (symbol-package family))
         (warm (intern (format nil "WARM-START-JOINTS/~A" family) home))
         (solve (intern (format nil "SOLVE-JOINTS/~A" family) home)))
    `(macrolet ,(apply #'joint-lane-operators operators)
       (defun ,warm (set v d start end)
         ,(format nil "Warm start the joints START..END of SET, ~D point joints at a time (~A). #J0LANE" width says)
         (declare (type joint-set set) (type f32-column v d) (type index start end) #.+kernel-policy+)
         (with-joint-columns (kind row-a row-b rax ray raz rbx rby rbz ima imb iia iib impulse-x impulse-y impulse-z)
             (joint-set-rows set)
           (do-joint-blocks (,width ,settle) (wide-point-warm-start) (warm-start-joints set v d j (1+ j))))
         nil)
       (defun ,solve (set v d inv-h use-bias start end)
         ,(format nil "Solve or relax the joints START..END of SET, ~D point joints at a time (~A). #J0LANE" width says)
         (declare (type joint-set set) (type f32-column v d) (type single-float inv-h) (type index start end)
                  #.+kernel-policy+)
         (with-joint-columns (kind row-a row-b rax ray raz rbx rby rbz sx sy sz ima imb iia iib
                              k11 k12 k13 k22 k23 k33 bias-rate mass-scale impulse-scale impulse-x impulse-y impulse-z)
             (joint-set-rows set)
           (if use-bias
               (do-joint-blocks (,width ,settle) (wide-point-solve t) (solve-joints set v d inv-h t j (1+ j)))
               (do-joint-blocks (,width ,settle) (wide-point-solve nil) (solve-joints set v d inv-h nil j (1+ j)))))
         nil))))

(define-joint-lanes avx2 8 "Eight lanes of AVX2, the upper halves cleared before scalar code. #J0LANE"
  (sb-simd-avx:vzeroupper)
  :aref sb-simd-avx:f32.8-aref :add sb-simd-avx:f32.8+ :sub sb-simd-avx:f32.8- :mul sb-simd-avx:f32.8*
  :broadcast sb-simd-avx:f32.8 :xor sb-simd-avx:f32.8-xor :gt sb-simd-avx:f32.8> :if* sb-simd-avx:f32.8-if
  :transpose with-rows-8 :scatter scatter-rows-8)

(define-joint-lanes sse 4 "Four lanes of SSE4.1. #J0LANE" nil
  :aref sb-simd-sse:f32.4-aref :add sb-simd-sse:f32.4+ :sub sb-simd-sse:f32.4- :mul sb-simd-sse:f32.4*
  :broadcast sb-simd-sse:f32.4 :xor sb-simd-sse:f32.4-xor :gt sb-simd-sse2:f32.4> :if* f32.4-select
  :transpose with-rows-4 :scatter scatter-rows-4)

(defmethod joint-kernels ((kernels avx2-kernels)) (values #'warm-start-joints/avx2 #'solve-joints/avx2))

(defmethod joint-kernels ((kernels sse-kernels)) (values #'warm-start-joints/sse #'solve-joints/sse))
;; Point joints in lanes:1 ends here

;; [[file:../physics.org::#L4NESW][Every core in lanes:1]]
(defun settle-ymm ()
  "Clear the upper halves of the ymm registers, after a worker's piece of AVX2 code. #L4NESW"
  (sb-simd-avx:vzeroupper))

(defmethod kernel-lanes ((kernels sse-kernels)) (values 4 nil))

(defmethod kernel-lanes ((kernels avx2-kernels)) (values 8 #'settle-ymm))
;; Every core in lanes:1 ends here
